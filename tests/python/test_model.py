"""The 1D objects from Python: the Lua API's names, messages and numbers."""
import numpy as np
import pytest

import dfle

CASE = """
channel = dfle.channel{ dx = 20, A_max = 1e6 }
m = dfle.model{ channel = channel, U = 5e-4,
  fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
  router = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300 },
  law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 } }
m:init_fluvial_steady()
run = m:run_to_steady{ tol = 1e-3, max_time = 2e7 }
for _, f in ipairs{"z", "S", "E_df", "E_f"} do
  for _, v in ipairs(m:get(f)) do print(string.format("%.17g", v)) end
end
fit = dfle.fit_slope_area(m)
print(string.format("%.17g %.17g %.17g", fit.S_df, fit.A_df, fit.r2))
"""


def case():
    channel = dfle.channel(dx=20, A_max=1e6)
    m = dfle.model(channel=channel, U=5e-4,
                   fluvial=dfle.fluvial.stochastic_threshold(k_e=5e-14),
                   router=dfle.router.empirical(M0=3000, gamma=0.5, mu=500, tau_y=300),
                   law=dfle.law.power(k_df=1e-4, alpha=6, beta=1))
    m.init_fluvial_steady()
    return m, m.run_to_steady(tol=1e-3, max_time=2e7)


def test_steady_state_bit_for_bit_as_lua(lua):
    m, run = case()
    assert run.converged and run["reason"] == "steady"
    ours = np.concatenate([m.get(f) for f in ("z", "S", "E_df", "E_f")])
    fit = dfle.fit_slope_area(m)
    theirs = [float(v) for v in lua(CASE)]
    assert len(theirs) == ours.size + 3
    assert np.array_equal(ours, np.array(theirs[:-3]))   # bit for bit
    assert [fit.S_df, fit.A_df, fit.r2] == theirs[-3:]


def test_steady_state_is_steady():
    # At steady state dz/dt = U - E_f - E_df = 0 on the nodes above the outlet.
    m, run = case()
    rate = m.U - m.get("E_f") - m.get("E_df")
    assert np.max(np.abs(rate[:-1])) <= 1e-3 * m.U


def test_fields_are_float64():
    m, _ = case()
    z = m.get("z")
    assert z.dtype == np.float64 and z.shape == (m.n,)
    assert np.all(z[:-1] > 0)       # views and copies: tests/python/test_fields.py
    assert "z" in list(m.fields())


def test_errors_are_the_lua_messages():
    with pytest.raises(dfle.Error, match=r"^dfle.channel: dx must be > 0 m \(got -1\)$"):
        dfle.channel(dx=-1)
    with pytest.raises(dfle.Error, match="unknown parameter 'dxx'"):
        dfle.channel(dxx=1)
    m = dfle.model()
    with pytest.raises(dfle.Error, match=r"dfle.model:run: years must be > 0"):
        m.run(years=0)
    with pytest.raises(AttributeError, match="dfle.model has no field 'foo'"):
        m.foo


def test_expected_failure_raises():
    # Lua returns nil, why; Python raises dfle.Error(why).
    with pytest.raises(dfle.Error):
        dfle.fit_slope_area({"A": [1.0, 2.0], "S": [0.1, 0.2]})


def test_methods_properties_and_components():
    ch = dfle.channel(dx=50, A_max=1e6)
    assert ch.n == len(ch.get("A")) and ch.dx == 50
    fl = dfle.fluvial.stream_power(K=1e-5, m=0.5, n=1)
    assert fl.name == "stream_power"
    m = dfle.model(channel=ch, fluvial=fl, router=False)
    assert m.fluvial.name == "stream_power" and m.router is None
    p = m.params()
    assert p["U"] == m.U
    m.set_U(1e-3)
    assert m.U == 1e-3
    assert repr(m).startswith("dfle.model(")


def test_closed_object_raises():
    m = dfle.model()
    with m:
        pass
    with pytest.raises(dfle.Error):
        m.run(years=10)


def test_owner_gone_components_live():
    m = dfle.model(channel=dfle.channel(dx=50))
    ch = m.channel
    del m
    assert ch.n > 0


def test_callable_U_of_t():
    calls = []

    def U(t):
        calls.append(t)
        return 5e-4

    m = dfle.model(channel=dfle.channel(dx=50), U=U)
    m.run(years=1000)
    assert calls and m.time == 1000


def test_callback_error_is_the_cause():
    def U(t):
        raise ValueError("no uplift here")

    with pytest.raises(dfle.Error) as e:
        dfle.model(channel=dfle.channel(dx=50), U=U).run(years=100)
    assert "no uplift here" in str(e.value)
    assert isinstance(e.value.__cause__, ValueError)


RATE = "function(c, p) return p.k * c.S ^ p.alpha * c.h end"
LAW_CASE = """
law = dfle.law.define{ name = "Lua", params = { k = 1e-4, alpha = 6 }, rate = %s }
m = dfle.model{ channel = dfle.channel{ dx = 20, A_max = 1e6 }, law = law }
m:run_to_steady{ tol = 1e-3 }
for _, v in ipairs(m:get("z")) do print(string.format("%%.17g", v)) end
""" % RATE


def test_custom_law_from_lua_source_compiles(lua):
    law = dfle.law.define(name="Lua", params={"k": 1e-4, "alpha": 6}, rate=RATE)
    m = dfle.model(channel=dfle.channel(dx=20, A_max=1e6), law=law)
    run = m.run_to_steady(tol=1e-3)
    assert run.converged
    assert law.compiled()["rate"] is True          # compiled, not run as Lua
    assert law.k == 1e-4
    assert np.array_equal(m.get("z"), np.array([float(v) for v in lua(LAW_CASE)]))


def test_lua_source_errors():
    with pytest.raises(dfle.Error):
        dfle.lua("function(c, p) return end end")
    with pytest.raises(dfle.Error, match="must be a function"):
        dfle.lua("42")


def test_warnings_are_python_warnings():
    with pytest.warns(dfle.Warning):
        dfle.model(U=5.0)  # m/yr: 5 m/yr is a unit mistake


def test_to_xarray():
    xr = pytest.importorskip("xarray")
    m, _ = case()
    ds = m.to_xarray()
    assert isinstance(ds, xr.Dataset)
    assert np.array_equal(ds["z"].values, m.get("z"))
    assert ds["x"].attrs["units"] == "m"


def test_reference_cycles_are_collected():
    import gc
    import weakref

    class Holder:
        pass

    h = Holder()
    h.m = dfle.model(channel=dfle.channel(dx=50))
    h.self = h                      # a cycle through a Python object
    w = weakref.ref(h.m)
    del h
    gc.collect()
    assert w() is None


def test_handles_stay_valid_after_arrays_and_results():
    m = dfle.model(channel=dfle.channel(dx=50))
    run = m.run_to_steady(tol=1e-3)
    z = m.get("z")
    del m
    import gc
    gc.collect()
    assert np.all(np.isfinite(z)) and run.converged
