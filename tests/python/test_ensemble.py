"""Ensembles, PAWN and the inversion from Python, through the driver layer."""
import numpy as np
import pytest

import dfle

LUA = """
ens = dfle.ensemble{ params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
  n = 6, seed = 1, out = "lua.csv", outputs = { "S_df", "A_df", "r2" },
  build = function(p)
    return dfle.model{ channel = dfle.channel{ dx = 50, A_max = 1e6 }, U = p.U,
                       law = dfle.law.power{ k_df = p.k_df } }
  end }
for i = 1, ens.n do print(string.format("%.17g %.17g", ens.data.S_df[i], ens.data.A_df[i])) end
"""


def build(p):
    return dfle.model(channel=dfle.channel(dx=50, A_max=1e6), U=p["U"],
                      law=dfle.law.power(k_df=p["k_df"]))


def run(tmp_path, build_fn):
    return dfle.ensemble(params={"k_df": {1: 5e-5, 2: 1e-3, "log": True}, "U": [1e-4, 1e-3]},
                         n=6, seed=1, out=str(tmp_path / "py.csv"),
                         outputs=["S_df", "A_df", "r2"], build=build_fn)


def test_python_build_as_lua(tmp_path, lua):
    ens = run(tmp_path, build)
    assert ens.n == 6 and ens.ok == 6 and ens.complete
    theirs = np.array([float(v) for v in lua(LUA)]).reshape(6, 2)
    assert np.array_equal(ens.data["S_df"], theirs[:, 0])
    assert np.array_equal(ens.data["A_df"], theirs[:, 1])


def test_lua_build_same_numbers(tmp_path):
    lua_build = dfle.lua("""function(p)
        return dfle.model{ channel = dfle.channel{ dx = 50, A_max = 1e6 }, U = p.U,
                           law = dfle.law.power{ k_df = p.k_df } }
      end""")
    a = run(tmp_path, build)
    (tmp_path / "py.csv").unlink()
    b = run(tmp_path, lua_build)
    assert np.array_equal(a.data["S_df"], b.data["S_df"])


def test_failed_build_is_a_failed_sample(tmp_path):
    def bad(p):
        raise RuntimeError("no model for you")
    ens = run(tmp_path, bad)
    assert ens.failed == 6
    assert "no model for you" in ens.data["reason"][0]


def test_to_pandas(tmp_path):
    pd = pytest.importorskip("pandas")
    ens = run(tmp_path, build)
    df = dfle.to_pandas(ens)
    assert isinstance(df, pd.DataFrame) and len(df) == 6
    assert list(df["S_df"]) == list(ens.data["S_df"])


PAWN_LUA = """
ens = dfle.ensemble{ params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
  n = 60, seed = 1, out = "pw.csv", outputs = { "S_df" },
  build = function(p)
    return dfle.model{ channel = dfle.channel{ dx = 100, A_max = 1e6 }, U = p.U,
                       law = dfle.law.power{ k_df = p.k_df } }
  end }
si = dfle.pawn(ens, { outputs = { "S_df" } })
print(string.format("%.17g %.17g", si.S_df.U.median, si.S_df.k_df.median))
"""


def test_pawn_as_lua(tmp_path, lua):
    ens = dfle.ensemble(params={"k_df": dfle.bounds(5e-5, 1e-3, log=True), "U": [1e-4, 1e-3]},
                        n=60, seed=1, out=str(tmp_path / "pw.csv"), outputs=["S_df"],
                        build=lambda p: dfle.model(channel=dfle.channel(dx=100, A_max=1e6),
                                                   U=p["U"], law=dfle.law.power(k_df=p["k_df"])))
    si, info = dfle.pawn(ens, outputs=["S_df"])
    assert info["S_df"]["N"] == 60
    assert [si["S_df"]["U"]["median"], si["S_df"]["k_df"]["median"]] == \
        [float(v) for v in lua(PAWN_LUA)]
    assert 0 <= si["S_df"]["U"]["minimum"] <= si["S_df"]["U"]["maximum"] <= 1


INVERT_LUA = """
truth = dfle.model{ U = 4e-4, channel = dfle.channel{ dx = 50 } }
truth:run_to_steady{}
res = dfle.invert{ data = { A = truth:get("A"), S = truth:get("S") }, channel = dfle.channel{ dx = 50 },
  build = function(p, ch) return dfle.model{ channel = ch, U = p.U } end,
  params = { U = { 1e-4, 1e-3, log = true } }, walkers = 8, steps = 30, burn = 10, seed = 1,
  out = "lua_chain.csv" }
print(string.format("%.17g %.17g", res.summary.U.median, res.summary.U.hi95))
"""


def test_invert_with_a_python_build_as_lua(tmp_path, lua):
    truth = dfle.model(U=4e-4, channel=dfle.channel(dx=50))
    truth.run_to_steady()
    res = dfle.invert(data={"A": truth.get("A"), "S": truth.get("S")},
                      channel=dfle.channel(dx=50),
                      build=lambda p, ch: dfle.model(channel=ch, U=p["U"]),
                      params={"U": dfle.bounds(1e-4, 1e-3, log=True)},
                      walkers=8, steps=30, burn=10, seed=1, out=str(tmp_path / "chain.csv"))
    U = res.summary["U"]
    assert [U["median"], U["hi95"]] == [float(v) for v in lua(INVERT_LUA)]
    assert U["lo95"] <= U["median"] <= U["hi95"]


def test_to_xarray_as_the_netcdf_file_opens(tmp_path):
    xr = pytest.importorskip("xarray")
    pytest.importorskip("netCDF4")
    ens = run(tmp_path, build)
    ds = ens.to_xarray()
    assert isinstance(ens, dfle.Ensemble) and ds.sizes == {"sample": 6}
    path = str(tmp_path / "ens.nc")
    ens.write_netcdf(path)
    with xr.open_dataset(path) as f:
        assert list(ds.data_vars) == list(f.data_vars)
        for name in ("index", "U", "k_df", "S_df", "A_df", "r2"):
            assert np.array_equal(ds[name].values, f[name].values), name
            assert ds[name].attrs.get("units") == f[name].attrs.get("units"), name
        assert ds["U"].attrs["units"] == "m/yr" and ds["A_df"].attrs["units"] == "m2"
        assert [s.decode() for s in f["status"].values] == list(ds["status"].values)
        assert ds.attrs["dfle_design"] == f.attrs["dfle_design"]
    assert np.array_equal(ds["S_df"].values, ens.data["S_df"])
    assert ens.to_pandas()["S_df"].tolist() == list(ens.data["S_df"])
