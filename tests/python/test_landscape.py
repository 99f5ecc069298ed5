"""Landscapes and DEMs from Python: grids shaped (ny, nx), the Lua API's
numbers, the GIL released, SIGINT stopping a run cleanly."""
import os
import signal
import threading
import time

import numpy as np
import pytest

import dfle

DATA = os.environ.get("DFLE_DATA_DIR", "")
TIF = os.path.join(DATA, "dem", "srtm_bigtujunga30m_utm11.tif")

LUA = """
ls = dfle.landscape{ nx = 24, ny = 16, dx = 30, noise = { amplitude = 1, seed = 3 } }
ls:run{ years = 2e4, dt = 1000 }
for _, v in ipairs(ls:get("z")) do print(string.format("%.17g", v)) end
"""


def small():
    return dfle.landscape(nx=24, ny=16, dx=30, noise={"amplitude": 1, "seed": 3})


def test_fields_shaped_ny_nx_and_as_lua(lua):
    ls = small()
    ls.run(years=2e4, dt=1000)
    z = ls.get("z")
    assert z.shape == (16, 24) and z.dtype == np.float64
    theirs = np.array([float(v) for v in lua(LUA)]).reshape(16, 24)
    assert np.array_equal(z, theirs)           # row-major, row 0 at the north
    assert ls.time == 2e4


def test_step_and_steady():
    ls = dfle.landscape(nx=40, ny=30, dx=30, noise={"seed": 2})
    s = ls.step(1000)
    assert s["dt"] == 1000 and ls.time == 1000
    run = ls.run_to_steady(max_time=5e7)
    assert run.converged and run.verified, run.note
    # Steady on the channels: |dz/dt| / U at most tol at the 0.99 quantile.
    ch = ls.get("channel") > 0
    assert ch.sum() == run.channel_cells > 0
    ratio = np.abs(ls.get("dzdt")[ch]) / 5e-4
    assert np.quantile(ratio, 0.99) <= 1e-3


def test_initial_z_from_a_2d_array():
    z0 = np.add.outer(np.arange(8.0), np.arange(6.0))          # (ny, nx)
    ls = dfle.landscape(nx=6, ny=8, dx=10, z=z0, noise=False, A0=100)
    assert np.array_equal(ls.get("z"), z0)
    with pytest.raises(dfle.Error, match="'z' has 47 values, the grid 6 x 8 = 48 cells"):
        dfle.landscape(nx=6, ny=8, dx=10, z=np.zeros(47), A0=100)


def test_to_xarray():
    xr = pytest.importorskip("xarray")
    ls = small()
    ds = ls.to_xarray(fields=["z", "A"])
    assert ds["z"].dims == ("y", "x") and ds.sizes == {"y": 16, "x": 24}
    assert ds["x"].values[0] == 15.0 and ds["y"].values[0] == 16 * 30 - 15.0


@pytest.mark.skipif(not os.path.exists(TIF), reason="no test DEM (DFLE_DATA_DIR)")
def test_dem_read_fill_flow_profile():
    dem = dfle.dem.read(TIF)
    dem.fill()
    dem.flow()
    p = dem.profile(outlet=[396887, 3799338])
    A = p.get("A")
    assert np.all(np.diff(A) >= 0)                             # downstream area grows
    fit = dfle.fit_slope_area(p)
    assert 0 < fit.r2 <= 1


def long_run():
    ls = dfle.landscape(nx=80, ny=80, dx=30)
    return ls, (lambda: ls.run(years=1e9, dt=100, max_steps=10 ** 8))


def test_sigint_stops_a_run_cleanly():
    ls, run = long_run()
    t = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    t.start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        run()
    t.join()
    assert time.monotonic() - start < 30
    assert 0 < ls.time < 1e9                   # stopped at a step, state kept
    assert np.all(np.isfinite(ls.get("z")))
    ls.run(years=200, dt=100)                  # and it runs again
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_gil_released_during_a_run():
    ls, run = long_run()
    ticks = []
    done = threading.Event()

    def worker():
        try:
            ls.run(years=3000, dt=100)
        finally:
            done.set()

    th = threading.Thread(target=worker)
    th.start()
    while not done.is_set():
        ticks.append(1)
        time.sleep(0.001)
    th.join()
    assert len(ticks) > 5                      # Python ran meanwhile
    assert ls.time == 3000


def test_threads_take_turns_with_the_same_numbers():
    # Two threads running models at once: the Lua state is shared under a
    # lock, and each gets the numbers it would get alone.
    def one():
        m = dfle.model(channel=dfle.channel(dx=20, A_max=1e6), U=5e-4)
        m.run_to_steady(tol=1e-3)
        return m.get("z")

    alone = one()
    out = [None] * 4

    def worker(k):
        out[k] = one()

    threads = [threading.Thread(target=worker, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for z in out:
        assert np.array_equal(z, alone)
