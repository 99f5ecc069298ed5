-- test_dem.lua - dfle.dem from Lua: reading, filling, routing, profiles
-- and networks on the Big Tujunga SRTM DEM ($DFLE_DATA_DIR/dem), their
-- use in the slope-area fit, plots and model channels, and the errors.
local T = ...
local tests = {}

local DATA = T.data .. "/dem/"
local TIF = DATA .. "srtm_bigtujunga30m_utm11.tif"
local ASC = DATA .. "srtm_bigtujunga30m_utm11.asc"
local BLACK = { 396887, 3799338 }   -- the paper's Fig. 1 outlets (UTM 11N)
local BLUE = { 384971, 3799277 }
local ORANGE = { 417896, 3792642 }  -- east of this DEM

-- One filled DEM for the tests that only read from it (reading and
-- filling it takes a third of a second).
local shared
local function filled()
    if not shared then
        shared = dfle.dem.read(TIF)
        shared:fill()
    end
    return shared
end

local function raises(fn, ...)
    local msg = T.raises_here(fn, ...)
    T.match(msg, "test_dem%.lua:%d+:")
    return msg
end

tests["read: GeoTIFF and ESRI ASCII give the same grid"] = function()
    local a, b = dfle.dem.read(TIF), dfle.dem.read(ASC)
    for _, d in ipairs{ a, b } do
        T.eq(d.nx, 1197)
        T.eq(d.ny, 643)
        T.eq(d.n, 1197 * 643)
        T.close(d.dx, 30, 1e-12)
        T.close(d.dy, 30, 1e-12)
        T.eq(d.epsg, 32611)
        T.eq(d.geographic, false)
        T.eq(d.nodata_cells, 0)
        T.eq(d.filled, false)
        T.eq(d.routed, false)
        T.eq(d.sinks, nil)
        T.eq(d.z_min, 315)
        T.eq(d.z_max, 2295)
        T.has(d.crs, "UTM zone 11N")
        T.has(d.crs_wkt, "UTM")
    end
    T.eq(a.path, TIF)
    for _, k in ipairs{ "E_min", "E_max", "N_min", "N_max" } do
        T.close(a.extent[k], b.extent[k], 0, 1e-6, k)
    end
    T.close(a.extent.E_min, 376313.655, 0, 1e-3)
    T.close(a.extent.N_max, 3807917.828, 0, 1e-3)
    T.has(tostring(a), "1197 x 643 cells of 30 x 30 m", "E 376314..412224", "N 3788628..3807918")
    local sa, sb = a:fill(), b:fill()
    T.eq(math.type(sa.raised), "integer")
    T.ok(sa.raised > 0)
    T.eq(sa.raised, sb.raised)
    T.eq(sa.max_raise, sb.max_raise)
    T.eq(a.filled, true)
    T.has(tostring(a), "filled")
    T.eq(a:flow(), a, "flow returns the DEM")
    T.eq(a.routed, true)
    T.eq(a.sinks, 0)
    T.ok(a.flats > 0)
    for _, p in ipairs{ BLACK, BLUE, { 400000, 3800000 } } do
        local za, Aa = a:at(p[1], p[2])
        local zb, Ab = b:at(p[1], p[2])
        T.eq(za, zb)
        T.eq(Aa, Ab)
    end
end

tests["profile: a Fig. 1 outlet gives a monotone channel and a sane fit"] = function()
    local dem = filled()
    for _, out in ipairs{ BLACK, BLUE } do
        local p = dem:profile{ outlet = out }
        T.eq(p.kind, "profile")
        T.eq(#p, p.n)
        T.ok(p.n > 100, "cells " .. p.n)
        T.ok(p.snap_distance <= 2 * math.sqrt(2) * 30 + 1e-9, "snapped " .. p.snap_distance)
        T.eq(p.given[1], out[1])
        T.eq(p.ds, 90)          -- default: 3 cells
        T.eq(p.dz, nil)
        local x, z, A, S, E, N, d = p:get("x"), p:get("z"), p:get("A"), p:get("S"), p:get("E"),
                                    p:get("N"), p:get("d")
        T.eq(#A, p.n)
        T.eq(A[1], 900)
        T.eq(x[1], 0)
        T.close(d[1], p.length, 1e-12)
        T.close(x[p.n], p.length, 1e-12)
        T.eq(p.outlet.E, E[p.n])
        T.eq(p.outlet[2], N[p.n])
        T.eq(p.head.E, E[1])
        T.eq(p.A_max, A[p.n])
        T.eq(p.A_min, 900)
        for i = 2, p.n do
            T.ok(A[i] >= A[i - 1], "area falls at cell " .. i)
            T.ok(z[i] <= z[i - 1], "elevation rises at cell " .. i)
            T.ok(S[i] >= 0 and S[i] < 10, "slope at cell " .. i)
        end
        local rcv = p:get("receiver")
        T.eq(rcv[1], 2)
        T.eq(rcv[p.n], 0)
        local fit = assert(dfle.fit_slope_area(p))
        T.ok(fit.r2 > 0.6, "R^2 " .. fit.r2)
        T.ok(fit.S_df > 0.1 and fit.S_df < 1.5, "S_df " .. fit.S_df)
        T.ok(fit.A_df > A[1] and fit.A_df < A[p.n], "A_df " .. fit.A_df)
        T.eq(type(fit.S_max_minus_S_ch), "number")
        T.ok(fit.bins.n_empty > 0)
        -- The pairs the fit used are p:slope_area()'s.
        local sa = p:slope_area()
        local same = assert(dfle.fit_slope_area{ A = sa.A, S = sa.S })
        T.eq(same.S_df, fit.S_df)
        T.eq(same.r2, fit.r2)
    end
end

tests["profile: from a head down to A_max, slope over a vertical interval"] = function()
    local dem = filled()
    local main = dem:profile{ outlet = BLACK }
    local E, N, A = main:get("E"), main:get("N"), main:get("A")
    local k = math.floor(main.n / 4)
    T.ok(A[k] < 3e6)
    local p = dem:profile{ head = { E[k], N[k] }, A_max = 3e6, dz = 10 }
    raises(function() return p.E end, "no field 'E'", "get") -- arrays come through p:get
    T.eq(p.dz, 10)
    T.eq(p.ds, nil)
    T.eq(p:get("E")[1], E[k])
    T.ok(p:get("A")[p.n] >= 3e6)
    T.ok(p:get("A")[p.n - 1] < 3e6)
    for i = 1, p.n do T.eq(p:get("A")[i], A[k + i - 1]) end
    -- To the grid's edge without A_max: longer than the catchment.
    local long = dem:profile{ head = { E[k], N[k] } }
    T.ok(long.n > main.n - k + 1)
    raises(function() return dem:profile{ head = { E[k], N[k] }, A_max = 1e3 } end,
           "single cell", "already reaches A_max")
end

tests["network: the catchment's cells, fit, CSV"] = function()
    local dem = filled()
    local net = dem:network{ A_min = 900, outlet = BLACK }
    T.eq(net.kind, "network")
    local A = net:get("A")
    -- Every cell of the catchment, each 900 m^2: they sum to its area.
    T.close(net.n * 900, net.A_max, 1e-12)
    T.eq(net.head, nil)
    T.ok(net.outlet ~= nil)
    T.eq(A[net.n], net.A_max)
    local fit = assert(dfle.fit_slope_area(net))
    T.ok(fit.r2 > 0.9, "R^2 " .. fit.r2)
    local channels = dem:network{ A_min = 1e5, outlet = BLACK }
    T.ok(channels.n < net.n)
    for _, a in ipairs(channels:get("A")) do T.ok(a >= 1e5) end
    local csv = T.tmpname(".csv")
    T.eq(channels:write_csv(csv), channels)
    local tab = T.read_csv(csv)
    T.eq(tab.header, "E,N,x,d,z,A,S,receiver,lon,lat")
    T.eq(tab.units.A, "m^2"); T.eq(tab.units.receiver, nil)
    T.eq(tab.units.lon, "degrees_east"); T.eq(tab.units.lat, "degrees_north")
    T.eq(#tab.rows, channels.n)
    -- where it came from: the DEM and the limits asked for
    T.has(table.concat(tab.comments, "\n"), "# profile network: dem=", "A_min=100000 m^2",
          '# crs: "WGS 84 / UTM zone 11N (EPSG:32611)"')
    -- Without an outlet: all channels of the DEM.
    local all = dem:network{ A_min = 1e7 }
    T.ok(all.n > 0)
    T.eq(all.outlet, nil)
    T.has(tostring(all), "network")
end

tests["plot: slope-area of a profile, and a model next to it"] = function()
    local dem = filled()
    local p = dem:profile{ outlet = BLUE }
    local png = T.tmpname(".png")
    dfle.plot.slope_area(p, png, nil, { title = "Blue catchment" })
    local img = assert(T.read_file(png))
    T.eq(img:sub(2, 4), "PNG")
    -- A model channel on the profile's A(x).
    local ch = p:channel{ dx = 20 }
    T.eq(getmetatable(ch), getmetatable(dfle.channel()))
    T.eq(ch.dx, 20)
    T.eq(ch.n, math.floor(p.length / 20) + 1)
    local A = ch:get("A")
    T.eq(A[1], 900)
    for i = 2, #A do T.ok(A[i] >= A[i - 1]) end
    local m = dfle.model{ channel = ch }
    m:init_fluvial_steady()
    m:run{ years = 10 }
    T.eq(m.n, ch.n)
    T.raises_here(function() return dem:network{ A_min = 1e6 }:channel() end, "network")
end

tests["errors: reading"] = function()
    raises(function() return dfle.dem.read("no/such/dem.tif") end,
           "dfle.dem: cannot read 'no/such/dem.tif': no such file")
    local txt = T.tmpname(".txt")
    T.write_file(txt, "not a raster\n")
    raises(function() return dfle.dem.read(txt) end, "dfle.dem: cannot read", txt)
    raises(function() return dfle.dem.read() end, "string expected")
    raises(function() return dfle.dem.read(TIF, { nodata = "x" }) end, "'nodata'", "number")
    raises(function() return dfle.dem.read(TIF, { NoData = -9999 }) end,
           "unknown parameter 'NoData'", "nodata, band, crs")
    raises(function() return dfle.dem.read(TIF, { band = 2 }) end, "band 2", TIF)
    raises(function() return dfle.dem.read(TIF, { band = 1.5 }) end, "band", "whole number")
    raises(function() return dfle.dem.read(TIF, { crs = 32611 }) end, "'crs'", "string")
    raises(function() return dfle.dem.read(TIF, { crs = "EPSG:nonsense" }) end, "EPSG:nonsense")
    -- NoData that the file does not declare.
    local d = dfle.dem.read(DATA .. "hugo_site_filled.asc", { nodata = -9999 })
    T.eq(d.nodata_cells, dfle.dem.read(DATA .. "hugo_site.asc").nodata_cells)
    T.ok(d.nodata_cells > 0)
    T.eq(d.crs, nil)
    T.eq(d.epsg, nil)
end

tests["errors: degrees, pits, outlets, options"] = function()
    local asc = T.tmpname(".asc")
    T.write_file(asc, "ncols 3\nnrows 3\nxllcorner -118.2\nyllcorner 34.2\n" ..
                      "cellsize 0.0002777777\n3 2 1\n3 2 1\n3 2 1\n")
    local geo = dfle.dem.read(asc, { crs = "EPSG:4326" })
    T.eq(geo.geographic, true)
    T.eq(geo.epsg, 4326)
    geo:fill()          -- filling needs no metres
    raises(function() return geo:flow() end, "geographic", "metres", "gdalwarp")
    raises(function() return geo:profile{ outlet = { -118.1997, 34.2003 } } end, "geographic")
    raises(function() return geo:at(-118.1997, 34.2003) end, "geographic")
    local nocrs = dfle.dem.read(asc)
    raises(function() return nocrs:network{ A_min = 1 } end, "look like degrees")

    local raw = dfle.dem.read(TIF)
    raises(function() return raw:profile{ outlet = BLACK } end, "pit", "dem:fill()")
    local dem = filled()
    raises(function() return dem:profile{ outlet = ORANGE } end,
           "dfle.dem: outlet (417896 E, 3792642 N) is outside the grid (E 376314..412224, " ..
           "N 3788628..3807918)")
    raises(function() return dem:at(0, 0) end, "outside the grid")
    -- longitude and latitude given to a projected DEM: say so
    raises(function() return dem:profile{ outlet = { -118.2, 34.3 } } end,
           "looks like longitude and latitude", "UTM zone 11N", "metres")
    raises(function() return dem:profile{} end, "'outlet' or 'head'")
    raises(function() return dem:profile() end, "table expected")
    raises(function() return dem:profile{ outlet = BLACK, head = BLUE } end, "not both")
    raises(function() return dem:profile{ outlet = { 1 } } end, "'outlet' must be {E, N}")
    raises(function() return dem:profile{ outlet = "here" } end, "'outlet' must be {E, N}", "string")
    raises(function() return dem:profile{ outlet = { 0 / 0, 1 } } end, "finite")
    raises(function() return dem:profile{ outlet = BLACK, A_max = 1e6 } end, "'A_max'", "head")
    raises(function() return dem:profile{ head = BLACK, A_min = 1e6 } end, "'A_min'", "outlet")
    raises(function() return dem:profile{ head = BLACK, radius = 10 } end, "'radius'")
    raises(function() return dem:profile{ outlet = BLACK, radius = -1 } end, "radius must be >= 0")
    -- Not snapped, the black outlet's own cell is a hillslope cell.
    raises(function() return dem:profile{ outlet = BLACK, radius = 0 } end, "single cell",
           "A = 900 m^2", "nothing drains into it")
    raises(function() return dem:profile{ outlet = BLACK, ds = 90, dz = 10 } end, "not both")
    raises(function() return dem:profile{ outlet = BLACK, ds = -1 } end, "slope interval")
    raises(function() return dem:profile{ outlet = BLACK, radus = 1 } end,
           "unknown parameter 'radus'", "radius")
    raises(function() return dem:network{} end, "'A_min'", "required")
    raises(function() return dem:network{ A_min = 0 } end, "A_min must be > 0")
    raises(function() return dem:network{ A_min = 1e12 } end, "lower A_min")
    raises(function() return dem:network{ A_min = 1e5, radius = 5 } end, "'radius'")
    local p = dem:profile{ outlet = BLUE }
    raises(function() return p:get("Q") end, "no field 'Q'", "receiver")
    raises(function() return p:channel{ dx = -5 } end, "dx must be > 0")
    raises(function() return p:channel{ dt = 5 } end, "unknown parameter 'dt'")
    raises(function() return p:write_csv("/no/such/dir/p.csv") end, "/no/such/dir/p.csv")
    raises(function() return dfle.fit_slope_area(dem) end, "dfle.profile", "dfle.dem")
    -- <close> frees; later use is an error, not a crash.
    do
        local q <close> = dem:profile{ outlet = BLUE }
        T.ok(q.n > 0)
        p = q
    end
    raises(function() return p:get("A") end, "closed")
    T.eq(tostring(p), "dfle.profile (closed)")
end

-- The DEM's products as GeoTIFF bands, read back through dfle.dem.read.
tests["write_geotiff: filled z, area, D8, slope and channel mask, read back"] = function()
    local dem = filled()
    local tif = T.tmpname(".tif")
    T.ok(rawequal(dem:write_geotiff(tif, { layers = { "z", "area", "d8", "slope", "channels" },
                                           A_min = 1e6 }), dem))
    local E, N = BLACK[1], BLACK[2]
    local z, A = dem:at(E, N)
    local band = {}
    -- codes and a mask carry no unit; area (m2) and slope (1) are no
    -- elevations, and the reader says so (their values: test_raster.c)
    for _, k in ipairs{ 1, 3, 5 } do band[k] = dfle.dem.read(tif, { band = k }) end
    raises(function() return dfle.dem.read(tif, { band = 2 }) end, "are in 'm2'; dfle needs metres")
    raises(function() return dfle.dem.read(tif, { band = 4 }) end, "are in '1'; dfle needs metres")
    T.eq(band[1].nx, dem.nx)
    T.eq(band[1].epsg, 32611, "the CRS goes with the grid")
    T.close(band[1].extent.E_min, dem.extent.E_min, 0, 1e-6)
    T.eq(band[1]:at(E, N), z)
    T.ok(A >= 900)
    -- D8 codes are ESRI's powers of two, 0 where nothing drains out
    local seen = {}
    for _, c in ipairs{ 0, 1, 2, 4, 8, 16, 32, 64, 128 } do seen[c] = true end
    local d8 = band[3]
    for k = 1, 200 do
        local e = dem.extent.E_min + 15 + 30 * (k * 7 % dem.nx)
        local n = dem.extent.N_max - 15 - 30 * (k * 13 % dem.ny)
        T.ok(seen[d8:at(e, n)], "D8 code " .. tostring(d8:at(e, n)))
        local a = dem:at(e, n)
        local mask = band[5]:at(e, n)
        local _, area = dem:at(e, n)
        T.eq(mask, area >= 1e6 and 1 or 0)
        T.ok(a ~= nil)
    end
    raises(function() return dem:write_geotiff(tif, { layers = { "channels" } }) end, "needs A_min")
    raises(function() return dem:write_geotiff(tif, { layers = { "zz" } }) end, "a layer must be 'z', 'area', 'd8', 'slope' or 'channels' (got 'zz')")
    raises(function() return dem:write_geotiff(tif, { layers = { "z", "z" } }) end, "listed twice")
    raises(function() return dem:write_geotiff("/no/such/dir/x.tif") end, "/no/such/dir/x.tif")
    raises(function() return dem:write_geotiff(T.tmpname(".png")) end,
           "is not the name of a GeoTIFF: the file is a GeoTIFF, so its name must end in .tif or .tiff")
end

return tests
