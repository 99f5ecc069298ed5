"""Ensembles and inversions on worker threads from Python: a build given
as Lua source runs in worker states of their own, with the numbers the
dfle command gives for the same script."""
import numpy as np
import pytest

import dfle

BUILD = """function(p)
    return dfle.model{ channel = dfle.channel{ dx = 50, A_max = 1e6 }, U = p.U,
                       law = dfle.law.power{ k_df = p.k_df } }
  end"""

ENSEMBLE_LUA = """
ens = dfle.ensemble{ params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
  n = 24, seed = 3, out = "lua.csv", outputs = { "S_df", "A_df" }, workers = 2,
  build = %s }
print(ens.workers)
for i = 1, ens.n do print(string.format("%%.17g %%.17g", ens.data.S_df[i], ens.data.A_df[i])) end
""" % BUILD


def spec(tmp_path, build, name):
    return dict(params={"k_df": dfle.bounds(5e-5, 1e-3, log=True), "U": [1e-4, 1e-3]},
                n=24, seed=3, out=str(tmp_path / name), outputs=["S_df", "A_df"], workers=2,
                build=build)


def test_a_lua_build_runs_on_workers_as_the_command(tmp_path, lua):
    ens = dfle.ensemble(**spec(tmp_path, dfle.lua(BUILD), "py.csv"))
    assert ens.workers == 2 and ens.ok == 24
    out = lua(ENSEMBLE_LUA)
    assert int(out[0]) == 2
    theirs = np.array([float(v) for v in out[1:]]).reshape(24, 2)
    assert np.array_equal(ens.data["S_df"], theirs[:, 0])     # bit for bit
    assert np.array_equal(ens.data["A_df"], theirs[:, 1])


def test_a_python_build_runs_in_the_calling_thread(tmp_path):
    def build(p):
        return dfle.model(channel=dfle.channel(dx=50, A_max=1e6), U=p["U"],
                          law=dfle.law.power(k_df=p["k_df"]))
    a = dfle.ensemble(**spec(tmp_path, build, "a.csv"))
    assert a.workers == 1                                      # workers = 2 asked
    b = dfle.ensemble(spec(tmp_path, dfle.lua(BUILD), "b.csv"))  # one table, as in Lua
    assert b.workers == 2
    assert np.array_equal(a.data["S_df"], b.data["S_df"])


def test_calls_before_do_not_confuse_the_workers(tmp_path):
    # The workers' call is the main state's next one, however many came before.
    first = dfle.ensemble(**spec(tmp_path, dfle.lua(BUILD), "1.csv"))
    second = dfle.ensemble(**spec(tmp_path, dfle.lua(BUILD), "2.csv"))
    assert second.workers == 2
    assert np.array_equal(first.data["S_df"], second.data["S_df"])


INVERT_BUILD = "function(p) return dfle.model{ channel = dfle.channel{ dx = 50 }, U = p.U } end"
INVERT_LUA = """
truth = dfle.model{ U = 4e-4, channel = dfle.channel{ dx = 50 } }
truth:run_to_steady{}
res = dfle.invert{ data = { A = truth:get("A"), S = truth:get("S") }, build = %s,
  params = { U = { 1e-4, 1e-3, log = true } }, walkers = 8, steps = 30, burn = 10, seed = 1,
  workers = 2, out = "lua_chain.csv" }
print(string.format("%%.17g %%.17g %%.17g", res.summary.U.median, res.summary.U.lo95,
                    res.summary.U.hi95))
""" % INVERT_BUILD


def test_an_inversion_on_workers_as_the_command(tmp_path, lua):
    truth = dfle.model(U=4e-4, channel=dfle.channel(dx=50))
    truth.run_to_steady()
    res = dfle.invert(data={"A": truth.get("A"), "S": truth.get("S")},
                      build=dfle.lua(INVERT_BUILD),
                      params={"U": dfle.bounds(1e-4, 1e-3, log=True)}, walkers=8, steps=30,
                      burn=10, seed=1, workers=2, out=str(tmp_path / "chain.csv"))
    U = res.summary["U"]
    assert [U["median"], U["lo95"], U["hi95"]] == [float(v) for v in lua(INVERT_LUA)]
    assert U["lo95"] <= 4e-4 <= U["hi95"]






def test_sigint_stops_an_ensemble_on_workers_and_it_resumes(tmp_path):
    # Ctrl-C mid-ensemble: KeyboardInterrupt, the finished rows kept; the
    # same call again resumes and ends with the rows of a run never stopped.
    import os
    import signal
    import threading

    heavy = dfle.lua("""function(p)
        return dfle.model{ channel = dfle.channel{ dx = 5, A_max = 1e7 }, U = p.U,
                           law = dfle.law.power{ k_df = p.k_df } }
      end""")

    def call(name):
        return dfle.ensemble(params={"k_df": dfle.bounds(5e-5, 1e-3, log=True),
                                     "U": [1e-4, 1e-3]},
                             n=3000, seed=2, out=str(tmp_path / name), outputs=["S_df"],
                             build=heavy, workers=2)

    timer = threading.Timer(0.15, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            call("stopped.csv")
    finally:
        timer.join()
    path = tmp_path / "stopped.csv"
    kept = 0
    if path.exists():
        kept = sum(1 for line in open(path) if line[:1] not in ("#", "")) - 1
    assert kept < 3000                           # stopped before the end
    resumed = call("stopped.csv")
    assert resumed.complete and resumed.ok == 3000
    fresh = call("fresh.csv")
    assert np.array_equal(resumed.data["S_df"], fresh.data["S_df"])
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
