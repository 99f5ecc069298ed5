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
        """The fields as an xarray.Dataset on the coordinate x [m] (needs
        xarray): each with its unit, the model's record (its components'
        parameters, U, time) as attributes under the names its NetCDF
        files give them (router_M0, model_U, ...)."""
        import xarray as xr
        x = self.get("x")
        data = {f: ("x", self.get(f), _labels(False, f)) for f in self.fields() if f != "x"}
        data["z"][2]["long_name"] = "elevation above the outlet"
        return xr.Dataset(data, coords={"x": ("x", x, {"units": "m", "axis": "X",
                                                       "long_name": "distance from the channel head"})},
                          attrs=_attrs(self)[0])


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
        """The fields (default all) as an xarray.Dataset on (y, x) cell
        centres [m], labelled as the landscape's NetCDF files label them
        (needs xarray): units, long and CF standard names, the CRS as a
        grid mapping variable `crs` (crs_wkt, spatial_ref) where the
        landscape has one, and its record as attributes under the files'
        names (landscape_dx, router_M0, ...)."""
        import xarray as xr
        nx, ny, dx, dy = self.nx, self.ny, self.dx, self.dy
        x = self.x0 + dx * (_np.arange(nx) + 0.5)
        y = self.y0 - dy * (_np.arange(ny) + 0.5)
        attrs, crs = _attrs(self)
        names = fields if fields is not None else list(self.fields())
        data = {}
        for f in names:
            labels = _labels(True, f)
            if crs is not None:
                labels["grid_mapping"] = "crs"
            data[f] = (("y", "x"), self.get(f), labels)
        if crs is not None:
            data["crs"] = ((), _np.int32(0), {"crs_wkt": crs, "spatial_ref": crs})
        coords = {"x": ("x", x, {"units": "m", "standard_name": "projection_x_coordinate",
                                 "long_name": "easting of the cell centre", "axis": "X"}),
                  "y": ("y", y, {"units": "m", "standard_name": "projection_y_coordinate",
                                 "long_name": "northing of the cell centre", "axis": "Y"})}
        return xr.Dataset(data, coords=coords, attrs=attrs)


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


def _labels(landscape, name):
    """A field's attributes as dfle's NetCDF files write them."""
    label = _dfle.field_label(landscape, name)
    if label is None:
        return {}
    unit, dfle_unit, long_name, standard_name = label
    out = {}
    if unit is not None:
        out["units"] = unit
    if dfle_unit is not None:
        out["dfle_units"] = dfle_unit
    if long_name is not None:
        out["long_name"] = long_name
    if standard_name is not None:
        out["standard_name"] = standard_name
    return out


def _attrs(obj):
    """(attributes, crs): the object's record as its NetCDF files carry it."""
    attrs, crs = _dfle.attrs(obj)
    return {str(k): v for k, v in attrs.items()}, crs


# The functions law.define (rate, factor, integrand, frequency) and
# router.define (flow) take.
_SOURCES = ("rate", "factor", "integrand", "frequency", "flow")


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
