"""Python faces of dfle's object types: grids shaped (ny, nx), xarray,
custom laws from Lua source."""
import numpy as _np

from . import _dfle

_classes = None


class Model(_dfle.LuaRef):
    """dfle.model: fields are numpy float64 arrays along the channel.

    get("x"), get("A"), get("w") and get("z") are read-only views of the
    model's memory (they follow runs and set_z, and keep the model
    alive); every other field is a copy, evaluated when asked.
    """

    def get(self, name):
        v = self._field(name)
        return v if v is not None else self._index("get")(name)

    def to_xarray(self):
        """The fields as an xarray.Dataset on the coordinate x [m] (needs xarray)."""
        import xarray as xr
        units = {"x": "m", "A": "m^2", "w": "m", "z": "m", "S": "1", "E_f": "m/yr",
                 "E_df": "m/yr", "dzdt": "m/yr", "M": "m^3", "Q": "m^3/s", "h": "m",
                 "v": "m/s", "t_p": "s", "tau": "Pa", "Theta": "1"}
        x = self.get("x")
        data = {f: ("x", self.get(f), {"units": units.get(f, "")})
                for f in self.fields() if f != "x"}
        return xr.Dataset(data, coords={"x": ("x", x, {"units": "m"})},
                          attrs={"time_yr": self.time, "U_m_per_yr": self.U,
                                 "model": repr(self)})


class Landscape(_dfle.LuaRef):
    """dfle.landscape: get() returns an (ny, nx) array, row 0 at the north.

    get("z") is a read-only view of the elevations (it follows runs and
    set_z, and keeps the landscape alive); every other field is a copy,
    evaluated when asked.
    """

    def get(self, name):
        v = self._field(name)
        if v is None:
            v = _np.asarray(self._index("get")(name), dtype=float).reshape(self.ny, self.nx)
        return v

    def to_xarray(self, fields=None):
        """The fields as an xarray.Dataset on (y, x) cell centres [m] (needs xarray)."""
        import xarray as xr
        nx, ny, dx, dy = self.nx, self.ny, self.dx, self.dy
        x = self.x0 + dx * (_np.arange(nx) + 0.5)
        y = self.y0 - dy * (_np.arange(ny) + 0.5)
        names = fields if fields is not None else list(self.fields())
        ds = xr.Dataset({f: (("y", "x"), self.get(f)) for f in names},
                        coords={"x": ("x", x, {"units": "m"}), "y": ("y", y, {"units": "m"})},
                        attrs={"time_yr": self.time, "landscape": repr(self)})
        return ds


class Dem(_dfle.LuaRef):
    """dfle.dem: a raster read through GDAL."""


class Ensemble(_dfle.LuaRef):
    """The result of dfle.ensemble or dfle.gather: result.data holds one
    column per input, output, status and reason (numpy arrays and lists)."""

    def to_pandas(self):
        """The rows as a pandas.DataFrame indexed by sample (needs pandas)."""
        return to_pandas(self)

    def to_xarray(self):
        """The rows as an xarray.Dataset on the dimension sample, laid out
        as the file result.write_netcdf(path) writes: index, the inputs and
        the outputs (float64, with their units where dfle knows them, in
        UDUNITS's syntax, or as dfle_units where it has none),
        status and reason (str), the design and the rows file as
        attributes (needs xarray)."""
        import xarray as xr
        data = self["data"]
        inputs, outputs = list(self["inputs"]), list(self["outputs"])
        variables = {"index": ("sample", _np.asarray(data["index"], dtype=float),
                               {"units": "1",
                                "long_name": "sample index (row of the design, from 1)"})}
        for names, long_name in ((inputs, "input parameter"), (outputs, "output")):
            for name in names:
                attrs = {"long_name": long_name}
                unit = _dfle.known_unit(name)
                if unit is not None:     # as the file says it: UDUNITS's syntax
                    cf = _dfle.udunits(unit)
                    attrs["units" if cf is not None else "dfle_units"] = cf or unit
                variables[name] = ("sample", _np.asarray(data[name], dtype=float), attrs)
        variables["status"] = ("sample", _np.array(list(data["status"]), dtype=str),
                               {"long_name": "ok or failed"})
        variables["reason"] = ("sample", _np.array(list(data["reason"]), dtype=str),
                               {"long_name": "why a sample failed"})
        attrs = {"title": "dfle ensemble: one steady-state model per sample",
                 "source": "dfle " + _dfle.version, "dfle_version": _dfle.version}
        rows = self["file"] if "file" in self.keys() else None
        if isinstance(rows, str):
            try:
                with open(rows, encoding="utf-8", errors="replace") as f:
                    first = f.readline().rstrip("\r\n")
                if first.startswith("# "):
                    attrs["dfle_design"] = first[2:]
            except OSError:
                pass
            attrs["dfle_rows_file"] = rows
        for key in ("n", "count", "ok", "failed", "complete"):
            if key in self.keys():
                v = self[key]
                attrs["dfle_" + key] = int(v) if isinstance(v, bool) else v
        return xr.Dataset(variables, attrs=attrs)


_SOURCES = ("rate", "factor", "integrand", "frequency", "route")


def _with_sources(define, what):
    def wrapped(**kw):
        for k in _SOURCES:
            if isinstance(kw.get(k), str):
                kw[k] = _dfle.lua(kw[k], "=%s.%s" % (what, k))
        return define(**kw)
    wrapped.__doc__ = ("dfle.%s.define with the functions (%s) given as Lua source, "
                       "compiled as in the Lua API." % (what, ", ".join(_SOURCES)))
    return wrapped


def _install(pkg, classes):
    classes["dfle.model"] = Model
    classes["dfle.landscape"] = Landscape
    classes["dfle.dem"] = Dem
    classes["dfle.ensemble"] = Ensemble
    pkg.law["define"] = _with_sources(pkg.law["define"], "law")
    pkg.router["define"] = _with_sources(pkg.router["define"], "router")
    from . import _parallel
    pkg.ensemble = _parallel.wrap(pkg.ensemble, "ensemble")
    pkg.invert = _parallel.wrap(pkg.invert, "invert")


def to_pandas(result):
    """An ensemble's rows (result.data: one column per parameter, output,
    status and reason) as a pandas.DataFrame indexed by sample (needs pandas)."""
    import pandas as pd
    data = result["data"]
    cols = {k: list(data[k]) if not hasattr(data[k], "dtype") else data[k] for k in data.keys()}
    df = pd.DataFrame(cols)
    return df.set_index("index") if "index" in df else df
