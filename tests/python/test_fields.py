"""Fields as numpy arrays: the state and the geometry as read-only views
of the object's memory that keep it alive, every other field a copy."""
import gc

import numpy as np
import pytest

import dfle


def model():
    return dfle.model(channel=dfle.channel(dx=20, A_max=1e6), U=5e-4)


def test_state_and_geometry_are_read_only_views():
    m = model()
    for name in ("x", "A", "w", "z"):
        v = m.get(name)
        assert v.dtype == np.float64 and v.shape == (m.n,)
        assert not v.flags.writeable and not v.flags.owndata
        with pytest.raises(ValueError, match="read-only"):
            v[0] = 1.0                           # refused: the model would not see it
    z = m.get("z")
    before = z.copy()
    m.run(years=5e4)
    assert not np.array_equal(z, before)         # the view follows the run
    assert np.array_equal(z, m.get("z"))
    new = np.linspace(100.0, 0.0, m.n)
    m.set_z(new)                                 # set_z is the way in
    assert np.array_equal(z, new)


def test_derived_fields_are_copies_evaluated_when_asked():
    m = model()
    S = m.get("S")
    assert S.flags.writeable and S.flags.owndata
    m.run(years=5e4)
    S_now = m.get("S")
    assert not np.array_equal(S, S_now)          # the old copy did not follow
    # S is the slope of the current z (x increases downstream).
    x, z = m.get("x"), m.get("z")
    assert np.allclose(S_now[:-1], -np.diff(z) / np.diff(x), rtol=1e-12)
    S_now[:] = -1.0                              # writing a copy changes nothing
    assert np.all(m.get("S")[:-1] > 0)


def test_a_view_keeps_its_model_alive():
    def only_a_view():
        m = model()
        m.run(years=2e4)
        return m.get("z"), m.get("z").copy()

    z, expected = only_a_view()
    gc.collect()
    # Other models now take the memory a freed model would have left.
    others = [model() for _ in range(20)]
    for o in others:
        o.run(years=1e3)
    assert np.array_equal(z, expected)
    assert z.base.lua_type == "dfle.model"       # the holder is the model


def test_close_waits_for_the_last_view():
    m = model()
    z = m.get("z")
    expected = z.copy()
    m.close()                                    # doomed, not freed: a view lives
    assert np.array_equal(z, expected)
    del z
    gc.collect()
    with pytest.raises(dfle.Error, match="dfle.model has been closed"):
        m.get("z")
    with pytest.raises(dfle.Error, match="has been closed"):
        m.get("S")


def test_landscape_z_is_a_view_shaped_ny_nx():
    ls = dfle.landscape(nx=12, ny=8, dx=30, noise={"seed": 1})
    z = ls.get("z")
    assert z.shape == (8, 12) and not z.flags.writeable
    with pytest.raises(ValueError, match="read-only"):
        z[0, 0] = 0.0
    before = z.copy()
    ls.run(years=2e4, dt=1e3)
    assert not np.array_equal(z, before) and np.array_equal(z, ls.get("z"))
    A = ls.get("A")
    assert A.shape == (8, 12) and A.flags.writeable
    # Every cell drains at least itself: A >= one cell's area.
    assert np.all(A >= 30.0 * 30.0)
    del ls
    gc.collect()
    assert np.array_equal(z, z.base.get("z"))    # the view still holds it


def test_unknown_names_give_the_lua_message():
    with pytest.raises(dfle.Error, match=r"^dfle.model:get: no field 'zz' \(fields: x, A, w, z,"):
        model().get("zz")
    with pytest.raises(TypeError, match="a field name is a str"):
        model().get(3)
