"""Every kind of component, the DEM and a landscape from a DEM, from
Python and from Lua: the same numbers, bit for bit (the same code runs)."""
import os

import numpy as np
import pytest

import dfle

DATA = os.environ.get("DFLE_DATA_DIR", "")
TIF = os.path.join(DATA, "dem", "srtm_bigtujunga30m_utm11.tif")
OUTLET = [396887, 3799338]
needs_dem = pytest.mark.skipif(not os.path.exists(TIF), reason="no test DEM (DFLE_DATA_DIR)")

FLOW = """function(c, p)
  c.h = p.h0 * c.S ^ 0.1
  c.v = p.v0 * c.S ^ 0.5
  c.t_p = 30
  return c.A < p.A_stop
end"""

# Each case: the Lua expression of a model's components, and the same in Python.
CASES = {
    "stream power, inertial law": (
        "fluvial = dfle.fluvial.stream_power{ K = 2e-5, m = 0.5, n = 1 }, "
        "law = dfle.law.inertial{}",
        lambda: dict(fluvial=dfle.fluvial.stream_power(K=2e-5, m=0.5, n=1),
                     law=dfle.law.inertial())),
    "excess stress": (
        "law = dfle.law.excess_stress{ k = 2e-9, tau_c = 400, p = 1.5 }",
        lambda: dict(law=dfle.law.excess_stress(k=2e-9, tau_c=400, p=1.5))),
    "a router from Lua source": (
        "router = dfle.router.define{ name = 'mine', params = { h0 = 2, v0 = 10, A_stop = 3e5 },"
        " flow = %s }" % FLOW,
        lambda: dict(router=dfle.router.define(name="mine", params={"h0": 2, "v0": 10,
                                                                    "A_stop": 3e5}, flow=FLOW))),
}


def lua_script(parts, method):
    return """
m = dfle.model{ channel = dfle.channel{ dx = 25, A_max = 1e6 }, U = 4e-4, %s }
run = m:run_to_steady{ tol = 1e-3, method = "%s" }
print(run.converged)
for _, f in ipairs{"z", "E_f", "E_df"} do
  for _, v in ipairs(m:get(f)) do print(string.format("%%.17g", v)) end
end
""" % (parts, method)


@pytest.mark.parametrize("name", sorted(CASES))
@pytest.mark.parametrize("method", ["direct", "implicit"])
def test_components_as_lua(lua, name, method):
    parts, python = CASES[name]
    m = dfle.model(channel=dfle.channel(dx=25, A_max=1e6), U=4e-4, **python())
    run = m.run_to_steady(tol=1e-3, method=method)
    out = lua(lua_script(parts, method))
    assert run.converged == (out[0] == "true")
    ours = np.concatenate([m.get(f) for f in ("z", "E_f", "E_df")])
    assert np.array_equal(ours, np.array([float(v) for v in out[1:]]))


def test_component_properties_and_params():
    law = dfle.law.excess_stress(k=2e-9, tau_c=400, p=1.5)
    assert law.name == "excess_stress" and law.tau_c == 400 and law.params()["p"] == 1.5
    rt = dfle.router.define(name="mine", params={"h0": 2, "v0": 10, "A_stop": 3e5}, flow=FLOW)
    assert rt.name == "mine"
    with pytest.raises(dfle.Error, match="excess_stress"):
        dfle.law.excess_stress(tau_c=-1)


def test_process_router_as_lua(lua):
    script = """
m = dfle.model{ channel = dfle.channel{ dx = 50, A_max = 2e5 }, router = dfle.router.process{ M0 = 500 } }
m:init_fluvial_steady()
m:run{ years = 200 }
for _, v in ipairs(m:get("E_df")) do print(string.format("%.17g", v)) end
"""
    m = dfle.model(channel=dfle.channel(dx=50, A_max=2e5), router=dfle.router.process(M0=500))
    m.init_fluvial_steady()
    m.run(years=200)
    assert m.router.name == "process"
    E = m.get("E_df")
    assert np.any(E > 0)                        # the flow eroded somewhere
    assert np.array_equal(E, np.array([float(v) for v in lua(script)]))


@needs_dem
def test_dem_network_as_lua(lua):
    script = """
dem = dfle.dem.read("%s")
dem:fill()
dem:flow()
net = dem:network{ A_min = 1e6, outlet = { %d, %d } }
stem = net:main_stem()
for _, v in ipairs(stem:get("A")) do print(string.format("%%.17g", v)) end
""" % (TIF, OUTLET[0], OUTLET[1])
    dem = dfle.dem.read(TIF)
    dem.fill()
    dem.flow()
    net = dem.network(A_min=1e6, outlet=OUTLET)
    A = net.main_stem().get("A")
    assert np.all(np.diff(A) >= 0) and A[0] >= 1e6       # down the stem, from A_min
    assert np.array_equal(A, np.array([float(v) for v in lua(script)]))
    fit = dfle.fit_slope_area(net)
    assert 0 < fit.r2 <= 1


@needs_dem
def test_landscape_from_a_dem_as_lua(lua):
    script = """
dem = dfle.dem.read("%s"):resample{ dx = 120 }
ls = dfle.landscape{ dem = dem, outlet = { %d, %d } }
run = ls:run_to_steady{ max_time = 5e7 }
print(run.converged, ls.data_cells)
for _, v in ipairs(ls:get("z")) do print(string.format("%%.17g", v)) end
""" % (TIF, OUTLET[0], OUTLET[1])
    dem = dfle.dem.read(TIF).resample(dx=120)
    ls = dfle.landscape(dem=dem, outlet=OUTLET)
    run = ls.run_to_steady(max_time=5e7)
    assert run.converged and run.verified, run.note
    out = lua(script)
    assert out[:2] == ["true", str(ls.data_cells)]
    z = ls.get("z")
    assert z.shape == (ls.ny, ls.nx)
    theirs = np.array([float(v) for v in out[2:]]).reshape(ls.ny, ls.nx)
    assert np.array_equal(z, theirs, equal_nan=True)   # NaN off the catchment
    assert np.isnan(z).sum() == ls.n - ls.data_cells
    xr = pytest.importorskip("xarray")
    ds = ls.to_xarray(fields=["z"])
    assert isinstance(ds, xr.Dataset) and "UTM zone 11N" in ds["crs"].attrs["crs_wkt"]
    assert ds["x"].values[0] == ls.x0 + 60 and ds["y"].values[0] == ls.y0 - 60
