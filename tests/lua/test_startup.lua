-- test_startup.lua - GDAL and libnetcdf are loaded on first use: a
-- script that reads no DEM and writes no GeoTIFF or NetCDF file never
-- maps them (the dfle command, and build/dfle.so in a stock lua5.4), and
-- one that does maps each when it needs it and works as before.  A
-- fresh process each time: this one has long since loaded both.
local T = ...
local tests = {}

local q = T.shquote

-- Defines mapped(name): "true" if this process has mapped a file whose
-- name contains `name`, read from /proc/self/maps.
local PROBE = [[
local function mapped(name)
    local f = assert(io.open("/proc/self/maps"))
    local s = f:read("a")
    f:close()
    return tostring(s:find(name, 1, true) ~= nil)
end
local function report(when)
    print(when .. ": gdal=" .. mapped("libgdal") .. " netcdf=" .. mapped("libnetcdf") ..
          " hdf5=" .. mapped("libhdf5"))
end
]]

local function have_maps()
    local f = io.open("/proc/self/maps")
    if f then f:close() end
    return f ~= nil
end

tests["an empty script's process maps neither GDAL nor netCDF"] = function()
    T.ok(have_maps(), "this test reads /proc/self/maps (Linux)")
    local out, ok = T.run_dfle(PROBE .. "report('empty')\n")
    T.eq(ok, true, out)
    T.has(out, "empty: gdal=false netcdf=false hdf5=false")
    -- So does one that runs a model and writes CSV.
    local csv = T.tmpname(".csv")
    out, ok = T.run_dfle(PROBE .. ([[
local m = dfle.model{ channel = dfle.channel{ dx = 20 } }
m:run_to_steady{}
m:write_csv(%q)
report('model')
]]):format(csv))
    T.eq(ok, true, out)
    T.has(out, "model: gdal=false netcdf=false hdf5=false")
end

-- NetCDF first: GDAL's own netCDF driver brings libnetcdf with it.
tests["writing NetCDF maps netCDF, reading a DEM maps GDAL, each when used"] = function()
    local asc, nc, tif = T.tmpname(".asc"), T.tmpname(".nc"), T.tmpname(".tif")
    T.write_file(asc, "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 10\n" ..
                      "3 2 1\n3 2 1\n3 2 1\n")
    local out, ok = T.run_dfle(PROBE .. ([[
report('start')
local m = dfle.model{ channel = dfle.channel{ dx = 20 } }
m:run{ years = 200, record = { 100, 200 }, netcdf = %q }
report('netcdf')
local d = dfle.dem.read(%q)
assert(d.nx == 3 and d.ny == 3)
d:write_geotiff(%q)
assert(dfle.dem.read(%q).nx == 3)
report('dem')
]]):format(nc, asc, tif, tif))
    T.eq(ok, true, out)
    T.has(out, "start: gdal=false netcdf=false", "netcdf: gdal=false netcdf=true",
          "dem: gdal=true netcdf=true")
    T.ok(T.read_file(nc) ~= nil, "the NetCDF file is written")
end

tests["build/dfle.so in a stock lua5.4: requiring it maps neither library"] = function()
    if os.execute("command -v lua5.4 > /dev/null 2>&1") ~= true then
        return -- no stand-alone interpreter: nothing to check (install-deps installs it)
    end
    local so = T.root .. "/build/dfle.so"
    T.ok(io.open(so, "rb") ~= nil, "no " .. so .. " (run make)")
    local script = T.tmpname(".lua")
    T.write_file(script, PROBE .. ([[
package.cpath = %q
local dfle = require "dfle"
assert(dfle.model{ channel = dfle.channel{ dx = 20 } }:run_to_steady{}.converged)
report('lua5.4')
]]):format(T.root .. "/build/?.so"))
    local out, ok = T.sh("lua5.4 " .. q(script))
    T.eq(ok, true, out)
    T.has(out, "lua5.4: gdal=false netcdf=false hdf5=false")
end

return tests
