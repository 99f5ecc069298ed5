"""dfle.ensemble and dfle.invert on the driver's worker threads.

A worker runs the call in a Lua state of its own, so it needs the call
as Lua: the spec is written as Lua source, the build (or measure) as the
source it was given to dfle.lua.  A spec that holds a Python callable, or
a dfle object made in Python (a channel, a DEM), cannot be written so:
the call then runs in the calling state alone, as with workers = 1.
"""
import math as _math
import weakref as _weakref

import numpy as _np

from . import _dfle

# The Lua functions dfle.lua made, with their source and chunk name.
_sources = _weakref.WeakKeyDictionary()


def remember(fn, source, name):
    _sources[fn] = (source, name)
    return fn


class _NotLua(Exception):
    pass


def _string(s):
    if isinstance(s, str):
        s = s.encode("utf-8", "surrogateescape")
    out = []
    for byte in s:
        c = chr(byte)
        out.append(c if (c.isalnum() or c in " _-.,:;/+*=()[]{}<>!?#%&@^~|$'") and byte < 128
                   else "\\%03d" % byte)
    return '"' + "".join(out) + '"'


def _number(x):
    if isinstance(x, (bool, _np.bool_)):
        return "true" if x else "false"
    if isinstance(x, (int, _np.integer)):
        return "%d" % x
    x = float(x)
    if _math.isnan(x):
        return "(0/0)"
    if _math.isinf(x):
        return "(1/0)" if x > 0 else "(-1/0)"
    return x.hex()  # exact: Lua reads hexadecimal floats


def _key(k):
    if isinstance(k, str):
        return "[%s]" % _string(k)
    if isinstance(k, (int, _np.integer)) and not isinstance(k, bool):
        return "[%d]" % k
    raise _NotLua()


def _lua(v, depth=0):
    if depth > 32:
        raise _NotLua()
    if v is None:
        return "nil"
    if isinstance(v, (bool, int, float, _np.bool_, _np.integer, _np.floating)):
        return _number(v)
    if isinstance(v, (str, bytes)):
        return _string(v)
    if isinstance(v, _dfle.LuaRef):
        if v in _sources:
            source, name = _sources[v]
            return "assert(load(%s, %s, \"t\"))()" % (_string("return " + source), _string(name))
        raise _NotLua()
    if isinstance(v, _np.ndarray):
        # As the array would go to Lua: integers for integer and bool
        # arrays, else float64, read in C order.
        kind = _np.int64 if v.dtype.kind in "biu" else _np.float64
        v = _np.ascontiguousarray(v, dtype=kind).ravel().tolist()
    if isinstance(v, dict):
        return "{" + ", ".join("%s = %s" % (_key(k), _lua(x, depth + 1)) for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple)):
        return "{" + ", ".join(_lua(x, depth + 1) for x in v) + "}"
    raise _NotLua()


def script(call, spec):
    """The Lua source of dfle.<call>(spec), or None when spec cannot be written as Lua."""
    try:
        return "return dfle.%s(%s)\n" % (call, _lua(spec))
    except _NotLua:
        return None


def wrap(fn, call):
    def parallel(*args, **kw):
        if len(args) == 1 and not kw and isinstance(args[0], dict):
            spec = args[0]
        elif not args:
            spec = kw
        else:
            return fn(*args, **kw)     # as the Lua API takes it, and says why not
        source = script(call, spec)
        if source is None:
            return fn(*args, **kw)
        return _dfle.parallel(fn, source, dict(spec))
    parallel.__name__ = call
    parallel.__doc__ = (
        "dfle.%s, with the Lua API's named parameters.  With a build (and measure) "
        "given as dfle.lua source, samples run on worker threads (workers = N, "
        "default all cores), each in a Lua state of its own, with the numbers the "
        "dfle command gives; with a Python callable they run one after the other "
        "in the calling thread." % call)
    return parallel
