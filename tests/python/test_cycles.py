"""Reference cycles through Lua: a Python callable that refers to the
object using it is collected with it by gc.collect(), and a callable
still in use is never taken."""
import gc
import weakref

import numpy as np

import dfle


def landscape_with_a_callback():
    box = []

    def U(x, y, t=0):
        # Refers to the landscape that calls it: box -> ls -> Lua -> U.
        return 5e-4 if box and box[0].nx == 8 else 4e-4

    ls = dfle.landscape(nx=8, ny=8, dx=30, U=U, noise={"seed": 1})
    box.append(ls)
    return ls, U


def test_a_cycle_through_a_landscape_is_collected():
    def make():
        ls, U = landscape_with_a_callback()
        ls.run(years=2000, dt=1000)
        return weakref.ref(ls), weakref.ref(U)

    w_ls, w_U = make()
    gc.collect()
    assert w_ls() is None and w_U() is None


def test_a_cycle_through_a_model_law_is_collected():
    def make():
        holder = {}

        def rate(c, p):
            return holder["m"].U * 0 + p.k * c.S ** 2

        law = dfle.law.define(name="py", params={"k": 1e-3}, rate=rate)
        m = dfle.model(channel=dfle.channel(dx=100, A_max=1e6), law=law)
        holder["m"] = m
        m.run(years=1e3)
        return weakref.ref(m), weakref.ref(rate)

    w_m, w_rate = make()
    gc.collect()
    assert w_m() is None and w_rate() is None


def test_a_callable_in_use_survives_a_collection():
    ls, U = landscape_with_a_callback()
    del U
    gc.collect()                   # the cycle is alive: ls is held here
    ls.run(years=2000, dt=1000)    # U is called again, intact
    assert np.all(np.isfinite(ls.get("z")))
    assert ls.get("U")[0, 0] == 5e-4


def test_a_callable_shared_by_two_objects_stays_while_one_lives():
    box = []

    def U(x, y, t=0):
        return 5e-4 if box else 4e-4

    a = dfle.landscape(nx=8, ny=8, dx=30, U=U, noise={"seed": 1})
    b = dfle.landscape(nx=8, ny=8, dx=30, U=U, noise={"seed": 1})
    box.append(a)
    w_a = weakref.ref(a)
    del a, U
    gc.collect()
    b.run(years=2000, dt=1000)     # U, which a's cycle also holds, still works
    assert b.get("U")[0, 0] == 5e-4
    assert w_a() is not None       # a stays: its U is also b's (not collected, not broken)
