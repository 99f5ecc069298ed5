"""to_xarray() as the NetCDF files of the same object open: the same
values, coordinates, units, CRS and parameters."""
import numpy as np
import pytest

import dfle

xr = pytest.importorskip("xarray")
pytest.importorskip("netCDF4")

# Attributes of the file alone: the file's own (CF's, its history) and
# the run that wrote it (run_*), which the object's record does not hold.
FILE_ONLY = {"Conventions", "title", "source", "history", "comment", "date_created"}


def same_attrs(ds, f, skip=()):
    for key, value in ds.attrs.items():
        if key in skip:
            continue
        assert key in f.attrs, key
        assert f.attrs[key] == value, key
    for key in f.attrs:
        if key not in FILE_ONLY and not key.startswith("run") and key not in skip:
            assert key in ds.attrs, key


def test_landscape_as_its_netcdf_file(tmp_path):
    ls = dfle.landscape(nx=10, ny=7, dx=30, x0=396000, y0=3800000, crs="EPSG:32611",
                        noise={"seed": 4}, router=dfle.router.empirical(M0=2000),
                        law=dfle.law.power(k_df=2e-4))
    path = str(tmp_path / "ls.nc")
    ls.run(years=3000, dt=1000, record=[3000], netcdf=path, fields=["z", "A", "dzdt"])
    ds = ls.to_xarray(fields=["z", "A", "dzdt"])
    with xr.open_dataset(path) as f:
        for name in ("x", "y"):
            assert np.array_equal(ds[name].values, f[name].values), name
            assert ds[name].attrs == f[name].attrs, name
        for name in ("z", "A", "dzdt"):
            assert ds[name].dims == ("y", "x")
            assert np.array_equal(ds[name].values, f[name].isel(time=-1).values, equal_nan=True)
            assert ds[name].attrs == f[name].attrs, name
        for key in ("crs_wkt", "spatial_ref"):
            assert ds["crs"].attrs[key] == f["crs"].attrs[key]
        # landscape_time: the file says when its run started.
        same_attrs(ds, f, skip={"landscape_time", "dfle_cwd"})
    assert ds.attrs["router_M0"] == 2000 and ds.attrs["law_k_df"] == 2e-4
    assert ds.attrs["landscape_time"] == 3000 and ds.attrs["landscape_dx"] == 30
    assert "EPSG\",\"32611" in ds["crs"].attrs["crs_wkt"]


def test_landscape_without_crs_has_no_grid_mapping():
    ds = dfle.landscape(nx=6, ny=5, dx=10, A0=100).to_xarray(fields=["z"])
    assert "crs" not in ds and "grid_mapping" not in ds["z"].attrs
    assert ds["z"].attrs["units"] == "m" and ds["x"].attrs["units"] == "m"


def test_model_as_its_netcdf_file(tmp_path):
    m = dfle.model(channel=dfle.channel(dx=50, A_max=1e6), U=3e-4,
                   router=dfle.router.empirical(tau_y=250), law=dfle.law.power(alpha=5))
    path = str(tmp_path / "m.nc")
    m.run(years=2000, record=[2000], netcdf=path)
    ds = m.to_xarray()
    with xr.open_dataset(path) as f:
        assert np.array_equal(ds["x"].values, f["x"].values)
        assert ds["x"].attrs == f["x"].attrs
        assert np.array_equal(ds["z"].values, f["z"].isel(time=-1).values)
        assert ds["z"].attrs == f["z"].attrs
        same_attrs(ds, f, skip={"model_time", "dfle_cwd"})
    assert ds.attrs["model_U"] == 3e-4 and ds.attrs["router_tau_y"] == 250
    assert ds.attrs["law_alpha"] == 5 and ds.attrs["model_time"] == 2000
    assert ds["E_df"].attrs["units"] == "m/yr" and ds["A"].attrs["units"] == "m2"
    assert set(m.fields()) == set(ds.data_vars) | {"x"}


def test_closed_object_says_so():
    m = dfle.model()
    m.close()
    with pytest.raises(dfle.Error, match="has been closed"):
        m.to_xarray()
