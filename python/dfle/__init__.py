"""dfle from Python: the same engine, objects and messages as the Lua API.

Every constructor and method of the Lua API (doc/lua-api.md) is here
under the same name; keyword arguments are the Lua API's one table of
named parameters, with the same names, units and defaults::

    import dfle
    m = dfle.model(channel=dfle.channel(dx=10, A_max=8e6), U=5e-4)
    run = m.run_to_steady(tol=1e-3)
    z = m.get("z")                      # numpy float64 array (a copy)
    fit = dfle.fit_slope_area(m)

Errors raise dfle.Error with the Lua API's message; warnings are
dfle.Warning.  See doc/python.md.
"""
import gc as _gc
import threading as _threading

from . import _dfle
from . import _parallel

__all__ = ["Error", "Warning", "Table", "LuaRef", "lua", "version"]

version = _dfle.version
LuaRef = _dfle.LuaRef


class Error(Exception):
    """An error dfle reports: the message is the Lua API's, word for word."""


class Warning(UserWarning):  # noqa: A001 (dfle.Warning, as dfle.Error)
    """A warning dfle gives (an implausible value, a run that stopped short)."""


class Table(dict):
    """A result table: a dict whose keys also read as attributes (run.converged)."""

    def __getattr__(self, key):
        try:
            return self[key]
        except KeyError:
            raise AttributeError(
                "result has no field '%s' (fields: %s)" % (key, ", ".join(sorted(map(str, self))))
            ) from None

    def __dir__(self):
        return sorted(list(dict.__dir__(self)) + [k for k in self if isinstance(k, str)])


_classes = {}
_dfle._setup(Error, Warning, Table, _classes, _threading.main_thread().ident)
# Cycles through Lua (a callable that refers to the object using it)
# become visible to the collector's full runs.
_gc.callbacks.append(_dfle._gc)


def lua(source, name="=lua"):
    """A Lua function from its source, e.g. a custom law's rate::

        dfle.lua("function(c, p) return p.k * c.S ^ p.alpha end")

    It runs in dfle's Lua state (the module is the global `dfle` there),
    so a law made of such functions runs compiled, as in the Lua API.
    """
    return _parallel.remember(_dfle.lua(source, name), source, name)


_module = _dfle.module()


def _export(name):
    value = _module._index(name)
    globals()[name] = value
    return value


for _name in _module.keys():
    if isinstance(_name, str) and _name not in globals():
        _export(_name)

from . import _objects  # noqa: E402  (classes of the object types, custom laws)
from ._objects import Model, Landscape, Dem, Ensemble, to_pandas  # noqa: E402,F401

_objects._install(__import__(__name__), _classes)


def bounds(lo, hi, **options):
    """A parameter's range for dfle.ensemble, dfle.lhs and dfle.invert:
    Lua's {lo, hi, log = true} is bounds(lo, hi, log=True)."""
    table = {1: lo, 2: hi}
    table.update(options)
    return table
