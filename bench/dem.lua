-- dem.lua - DEM conditioning and routing speed: priority-flood fill, D8
-- with flats resolved and drainage area on the Big Tujunga SRTM DEM
-- (1197 x 643 cells of 30 m), best of several repetitions, in cells per
-- second.  Reading (GDAL) is timed apart.
--
--   dfle -q bench/dem.lua [repetitions]

local reps = tonumber(arg and arg[1]) or 5
local data = os.getenv("DFLE_DATA_DIR")
local path = (data or "") .. "/dem/srtm_bigtujunga30m_utm11.tif"
local probe = data and io.open(path)
if not probe then
  print("dem: skipped: needs dem/srtm_bigtujunga30m_utm11.tif under DFLE_DATA_DIR")
  return
end
probe:close()

local best = { read = math.huge, fill = math.huge, flow = math.huge, total = math.huge }
local dem, stats
for _ = 1, reps do
  local t0 = os.clock()
  dem = dfle.dem.read(path)
  local t1 = os.clock()
  stats = dem:fill()
  local t2 = os.clock()
  dem:flow()
  local t3 = os.clock()
  best.read = math.min(best.read, t1 - t0)
  best.fill = math.min(best.fill, t2 - t1)
  best.flow = math.min(best.flow, t3 - t2)
  best.total = math.min(best.total, t3 - t1)
end

local n = dem.n
print(("DEM fill + D8 + drainage area (Big Tujunga SRTM, %d x %d = %d cells): %.3f s CPU " ..
       "(best of %d)"):format(dem.nx, dem.ny, n, best.total, reps))
print(("  %.3g cells per second; fill %.3f s (%.3g cells/s, %d cells raised), D8 + flats + " ..
       "area %.3f s (%.3g cells/s, %d cells on flats); GDAL read %.3f s")
      :format(n / best.total, best.fill, n / best.fill, stats.raised, best.flow, n / best.flow,
              dem.flats, best.read))
