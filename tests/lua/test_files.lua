-- test_files.lua - the files GIS and CF tools read, from the Lua side:
-- crs = for synthetic grids, GeoTIFF names, restarts from a run's own
-- output (ls:set_z from a dfle.dem or a NetCDF record, checked against
-- the grid), the crop of a catchment's series, dem:resample, dem:crop,
-- GeoPackages, and, where Debian's python3-xarray is installed, xarray
-- decoding every NetCDF file without a warning.  The files' contents are
-- read back with libnetcdf, GDAL and OGR in tests/test_netcdf.c,
-- test_raster.c and test_vector.c.
local T = ...
local tests = {}

local function raises(fn, ...) return T.raises_here(fn, ...) end

local function synthetic(extra)
  local o = { nx = 10, ny = 8, dx = 30, x0 = 390000, y0 = 3800000, U = 5e-4, A0 = 2700,
              noise = { seed = 4 } }
  for k, v in pairs(extra or {}) do o[k] = v end
  return dfle.landscape(o)
end

tests["crs = : checked through GDAL, in metres, kept by every file and ls:dem()"] = function()
  local ls = synthetic{ crs = "EPSG:32611" }
  local d = ls:dem()
  T.eq(d.epsg, 32611, "ls:dem() keeps the CRS")
  T.eq(d.crs, "WGS 84 / UTM zone 11N")
  local tif = T.tmpname(".tif")
  ls:write_geotiff(tif, { "z", "A" })
  T.eq(dfle.dem.read(tif).epsg, 32611, "the GeoTIFF's CRS")
  raises(function() return dfle.landscape{ nx = 4, ny = 4, crs = "EPSG:4326" } end,
         "dfle.landscape: crs: WGS 84 (EPSG:4326) is a geographic CRS (degrees)")
  raises(function() return dfle.landscape{ nx = 4, ny = 4, crs = "nowhere" } end,
         "dfle.landscape: crs: 'nowhere' is not a CRS GDAL understands")
  raises(function() return dfle.landscape{ nx = 4, ny = 4, crs = 32611 } end,
         "is not a CRS GDAL understands")
  local dem = dfle.dem.read(tif)
  raises(function() return dfle.landscape{ dem = dem, crs = "EPSG:32611" } end,
         "'crs' comes from the DEM; do not give it with 'dem'")
end

tests["write_geotiff: the name must say GeoTIFF"] = function()
  local ls = synthetic()
  raises(function() return ls:write_geotiff(T.tmpname(".png")) end,
         "is not the name of a GeoTIFF: the file is a GeoTIFF, so its name must end in .tif or .tiff")
  local up = T.tmpname(".TIF")
  T.ok(rawequal(ls:write_geotiff(up), ls))
end

tests["set_z from a GeoTIFF the landscape wrote: the same surface"] = function()
  local ls = synthetic{ crs = "EPSG:32611" }
  ls:run{ years = 2e3, dt = 1e3 }
  local z = ls:get("z")
  local tif = T.tmpname(".tif")
  ls:write_geotiff(tif)
  local other = synthetic{ crs = "EPSG:32611", noise = { seed = 9 } }
  T.ok(rawequal(other:set_z(dfle.dem.read(tif)), other))
  local back = other:get("z")
  for i = 1, #z do T.eq(back[i], z[i], "cell " .. i) end
  -- a DEM on another grid is refused, naming what differs
  local shifted = synthetic{ x0 = 390015 }
  raises(function() return shifted:set_z(dfle.dem.read(tif)) end,
         "the DEM's grid (cells of 30.0 x 30.0 m, north-west corner 390000.0 E, 3800000.0 N) is "
         .. "not the landscape's (30.0 x 30.0 m, 390015.0 E")
  local small = dfle.landscape{ nx = 4, ny = 4, dx = 30 }
  raises(function() return small:set_z(dfle.dem.read(tif)) end,
         "the DEM has 10 x 8 cells, the landscape 4 x 4")
  raises(function() return small:set_z({}) end, "give an array of 16 elevations, a dfle.dem")
  raises(function() return small:set_z("x") end, "got string")
end

tests["set_z from a NetCDF record, by number or time; the grid must match"] = function()
  local ls = synthetic()
  local nc = T.tmpname(".nc")
  local z0 = ls:get("z")
  ls:run{ years = 3e3, dt = 1e3, record = { 0, 1e3, 3e3 }, netcdf = nc, fields = { "z", "A" },
          float32 = false }
  local z3 = ls:get("z")
  local fresh = synthetic{ noise = { seed = 11 } }
  fresh:set_z{ netcdf = nc, record = 3 }
  local got = fresh:get("z")
  for i = 1, #z3 do T.eq(got[i], z3[i], "record 3, cell " .. i) end
  fresh:set_z{ netcdf = nc, time = 0 }
  got = fresh:get("z")
  for i = 1, #z0 do T.eq(got[i], z0[i], "t = 0, cell " .. i) end
  raises(function() return fresh:set_z{ netcdf = nc, record = 4 } end,
         "has 3 records (1 to 3); there is no record 4")
  raises(function() return fresh:set_z{ netcdf = nc, time = 500 } end,
         "has no record at t = 500 yr")
  raises(function() return fresh:set_z{ netcdf = nc } end, "give 'record' (1 = the first) or 'time'")
  raises(function() return fresh:set_z{ netcdf = nc, record = 1, time = 0 } end, "one of them")
  raises(function() return fresh:set_z{ netcdf = nc, record = 1, field = "E_df" } end,
         "has no field 'E_df'")
  raises(function() return fresh:set_z{ netcdf = nc, record = 1, turbo = 1 } end, "turbo")
  local other = synthetic{ dx = 20 }
  raises(function() return other:set_z{ netcdf = nc, record = 1 } end, "x coordinates")
  raises(function() return fresh:set_z{ netcdf = T.tmpname(".nc"), record = 1 } end,
         "no such file")
end

tests["a catchment's series covers its data only, and restarts in place"] = function()
  -- a bowl draining south, inside a ring of NoData two cells wide
  local nx, ny, z = 16, 14, {}
  for r = 0, ny - 1 do
    for c = 0, nx - 1 do
      local inside = r >= 2 and r < ny - 2 and c >= 3 and c < nx - 3
      z[r * nx + c + 1] = inside and (10 + math.abs(c - 8) + 0.5 * (ny - r)) or 0 / 0
    end
  end
  local ls = dfle.landscape{ nx = nx, ny = ny, dx = 30, z = z, noise = false, A0 = 2700,
                             nodata = "base_level" }
  local nc = T.tmpname(".nc")
  ls:run{ years = 2e3, dt = 1e3, record = { 2e3 }, netcdf = nc }
  -- the file holds the data's box: on the whole grid its ring is missing
  local full = dfle.landscape{ nx = nx, ny = ny, dx = 30, A0 = 2700, noise = { seed = 1 } }
  raises(function() return full:set_z{ netcdf = nc, record = 1 } end,
         "has no elevation at row 1, column 1, where the landscape has data")
  local whole = T.tmpname(".nc")
  full:run{ years = 1e3, dt = 1e3, record = { 1e3 }, netcdf = whole }
  local again = dfle.landscape{ nx = nx, ny = ny, dx = 30, z = z, noise = false,
                                nodata = "base_level" }
  again:set_z{ netcdf = nc, record = 1 }
  local want, got = ls:get("z"), again:get("z")
  for i = 1, #want do
    if want[i] == want[i] then T.eq(got[i], want[i], "cell " .. i) else T.ok(got[i] ~= got[i]) end
  end
  -- a record with data where the landscape has NoData is refused
  raises(function() return dfle.landscape{ nx = nx, ny = ny, dx = 30, z = z, noise = false }
                         :set_z{ netcdf = whole, record = 1 } end,
         "has an elevation at row 1, column 1, where the landscape has NoData")
end

tests["run options: what goes with what"] = function()
  local ls = synthetic()
  local nc = T.tmpname(".nc")
  raises(function() return ls:run{ years = 10, netcdf = nc } end, "'netcdf' goes with 'record'")
  raises(function() return ls:run{ years = 10, float32 = true } end, "'float32' goes with 'record'")
  raises(function() return ls:run{ years = 10, record = { 0 }, netcdf = nc, float32 = "yes" } end,
         "'float32' must be true or false")
  raises(function() return ls:run{ years = 10, record = { 0 }, netcdf = nc,
                                   fields = { "z", "z" } } end, "field 'z' is listed twice")
  local r = ls:run{ years = 10, record = { 0, 10 }, netcdf = nc, float32 = true,
                    fields = { "z", "channel" } }
  T.eq(r.recorded, 2)
end

tests["dem:resample and dem:crop: new DEMs through GDAL, same CRS"] = function()
  local dem = dfle.dem.read(T.data .. "/dem/srtm_bigtujunga30m_utm11.tif")
  local c = dem:resample{ dx = 90 }
  T.eq(c.dx, 90); T.eq(c.nx, 399); T.eq(c.ny, 215)
  T.eq(c.epsg, 32611)
  T.eq(c.path, nil, "made in memory")
  T.close(c.extent.E_min, dem.extent.E_min, 0, 1e-6)
  T.close(c.extent.N_max, dem.extent.N_max, 0, 1e-6)
  -- the mean of 3 x 3 cells: between their lowest and highest
  local E, N = 396887, 3799338
  local zc = c:at(E, N)
  T.ok(zc > 0)
  local b = dem:crop{ E_min = 390000, E_max = 400000, N_min = 3795000, N_max = 3802000 }
  T.eq(b.epsg, 32611)
  T.close(b.extent.E_min, 390000 - (390000 - dem.extent.E_min) % 30, 0, 1e-6)
  T.eq(b:at(E, N), dem:at(E, N), "the same cells")
  local n = dem:crop{ N_min = 3800000 } -- the other edges are the grid's
  T.close(n.extent.E_max, dem.extent.E_max, 0, 1e-6)
  local f = dem:resample{ dx = 15, method = "nearest" }
  T.eq(f:at(E, N), dem:at(E, N), "nearest: the cell it falls in")
  raises(function() return dem:resample{} end, "parameter 'dx' (the new cell size, m) is required")
  raises(function() return dem:resample{ dx = 90, method = "fast" } end,
         "method must be 'nearest', 'bilinear'")
  raises(function() return dem:resample{ dx = -5 } end, "dx and dy")
  raises(function() return dem:crop{} end, "give the box")
  raises(function() return dem:crop{ data = true, E_min = 1 } end, "not both")
  raises(function() return dem:crop{ E_min = 0, E_max = 10 } end, "does not overlap the grid")
  -- a catchment cut from the DEM, then its data's box
  local ls = dfle.landscape{ dem = dem, outlet = { E, N }, router = false }
  local box = ls:dem():crop{ data = true }
  T.ok(box.nx < 300 and box.ny < 300, ("the catchment's box: %d x %d"):format(box.nx, box.ny))
  T.eq(box.nodata_cells + ls.data_cells, box.n, "every data cell is in the box")
end

tests["GeoPackages: a network, a profile, a catchment"] = function()
  local dem = dfle.dem.read(T.data .. "/dem/srtm_bigtujunga30m_utm11.tif")
  dem:fill()
  local BLACK = { 396887, 3799338 }
  local p = dem:profile{ outlet = BLACK }
  local g1, g2, g3 = T.tmpname(".gpkg"), T.tmpname(".gpkg"), T.tmpname(".gpkg")
  T.ok(rawequal(p:write_gpkg(g1), p))
  local net = dem:network{ A_min = 1e5, outlet = BLACK }
  T.ok(rawequal(net:write_gpkg(g2), net))
  T.ok(rawequal(dem:write_gpkg(g3, { outlet = BLACK, A_min = 1e5 }), dem))
  for _, g in ipairs{ g1, g2, g3 } do
    T.eq(assert(T.read_file(g)):sub(1, 16), "SQLite format 3\0", "a GeoPackage is SQLite")
  end
  raises(function() return dem:write_gpkg(T.tmpname(".gpkg"), {}) end,
         "parameter 'outlet' ({E, N} in m) is required")
  raises(function() return p:write_gpkg(T.tmpname(".shp")) end, "must end in .gpkg")
  raises(function() return dem:write_gpkg(T.tmpname(".gpkg"), { outlet = { 0, 0 } }) end,
         "outside the grid")
end

-- xarray, as a user opens the files: time decoded to dates, the grid
-- mapping a coordinate, no warning.  Debian's python3-xarray only.
local PY = [[
import sys, warnings
import netCDF4  # its own import may warn about numpy; not the files'
import xarray as xr
warnings.simplefilter("error")
for path in sys.argv[1:]:
    ds = xr.open_dataset(path, decode_coords="all")
    if "time" in ds.coords and ds.time.size:
        assert ds.time.dtype == object, (path, ds.time.dtype)  # cftime dates
        assert ds.time.values[0].calendar == "noleap", path
    if "z" in ds and "x" in ds.dims and "y" in ds.dims:
        assert "crs" in ds.coords, (path, list(ds.coords))
        assert ds.crs.attrs["grid_mapping_name"] == "transverse_mercator", path
    ds.close()
print("xarray ok")
]]

tests["xarray decodes every NetCDF file (when Debian's python3-xarray is there)"] = function()
  local _, has = T.sh("/usr/bin/python3 -c 'import xarray, netCDF4' 2>/dev/null")
  if not has then
    print("skip - /usr/bin/python3 has no xarray and netCDF4 (python3-xarray, python3-netcdf4)")
    return
  end
  local m, l, e = T.tmpname(".nc"), T.tmpname(".nc"), T.tmpname(".nc")
  local model = dfle.model{ channel = dfle.channel{ dx = 50 } }
  model:run{ years = 100, record = { 50, 100 }, netcdf = m }
  local ls = synthetic{ crs = "EPSG:32611" }
  ls:run{ years = 2e3, dt = 1e3, record = { 0, 2e3 }, netcdf = l, fields = { "z", "channel" } }
  local ens = dfle.ensemble{ params = { U = { 1e-4, 1e-3 } }, n = 2, seed = 1,
                             out = T.tmpname(".csv"), workers = 1, outputs = { "S_df" },
                             build = function(p)
                               return dfle.model{ channel = dfle.channel{ dx = 50 }, U = p.U }
                             end }
  ens:write_netcdf(e)
  local py = T.tmpname(".py")
  T.write_file(py, PY)
  local out, ok = T.sh("/usr/bin/python3 " .. T.shquote(py) .. " " .. T.shquote(m) .. " " ..
                       T.shquote(l) .. " " .. T.shquote(e))
  T.ok(ok and out:find("xarray ok", 1, true), out)
end

return tests
