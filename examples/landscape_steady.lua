-- landscape_steady.lua - are steady landscapes steady? The default
-- run_to_steady{} on synthetic grids from noise, checked on what matters
-- (doc/landscape.md, "What steady means for a landscape").
--
-- Grids of 100^2 and 300^2 cells of 30 m (quick: 40^2 and 60^2) from
-- 2 m of seeded noise, every edge a base level, U = 0.5 mm/yr, channel
-- heads at 1 ha, three sets of processes: stream power with n = 1 (K =
-- 2e-5, m = 0.5) and n = 2.33 (K = 2.5e-5, m = 0.45), and the Fig. 9
-- debris-flow and fluvial components (the defaults).  For each, the
-- direct steady state must
--   - say converged, with at most 1 % of its channel cells above tol U
--     and its volume balance (outflux against uplift) within tol;
--   - for stream power, hold every channel cell within 1e-3 of the
--     analytical slope S = (U/K)^(1/n) A^(-m/n) (S_c where that is
--     steeper);
--   - be a fixed point: ten implicit steps of 1e4 yr from it leave the
--     channel criterion and the volume balance met.
-- A failed check raises an error (the script exits with status 1).
-- Draws steady_slope_area.png: every channel cell of the largest grids
-- with stream power against its analytical slope.
--
--   dfle examples/landscape_steady.lua [--quick] [output-directory]

local opts = dfle.args{
  usage = "dfle examples/landscape_steady.lua [options] [output-directory]",
  about = "Checks the default steady state of synthetic landscapes on their channels.",
  flags = { quick = "40^2 and 60^2 grids (for the test suite)" },
  output = true,
}
local sizes = opts.quick and { 40, 60 } or { 100, 300 }
local U, tol = 5e-4, 1e-3

local cases = {
  { name = "stream power, n = 1", K = 2e-5, m = 0.5, n = 1 },
  { name = "stream power, n = 2.33", K = 2.5e-5, m = 0.45, n = 2.33 },
  { name = "debris flows + rivers (Fig. 9)" },
}

local function build(case, size)
  local o = { nx = size, ny = size, dx = 30, U = U, A0 = 1e4,
              noise = { amplitude = 2, seed = 31 } }
  if case.K then
    o.router = false
    o.fluvial = dfle.fluvial.stream_power{ K = case.K, m = case.m, n = case.n }
  end
  return dfle.landscape(o)
end

-- Channel cells off the analytical slope by more than 1e-3, and the worst.
local function off_slope(ls, case)
  local A, S, ch, base = ls:get("A"), ls:get("S"), ls:get("channel"), ls:get("base")
  local off, worst = 0, 0
  for i = 1, #A do
    if ch[i] > 0 and base[i] == 0 then
      local Sa = math.min((U / case.K) ^ (1 / case.n) * A[i] ^ (-case.m / case.n), 0.8)
      local e = math.abs(S[i] / Sa - 1)
      off = off + (e > 1e-3 and 1 or 0)
      worst = math.max(worst, e)
    end
  end
  return off, worst
end

local failures, series = {}, {}
local function check(ok, what)
  if not ok then failures[#failures + 1] = what end
  return ok
end

print(("%-32s %7s %6s %7s %9s %10s %9s %10s %11s"):format("processes", "grid", "rounds", "CPU s",
      "channels", "above tol", "balance", "off 1e-3", "after 10x1e4"))
for _, case in ipairs(cases) do
  for _, size in ipairs(sizes) do
    local label = ("%s, %d^2"):format(case.name, size)
    local ls = build(case, size)
    local t0 = os.clock()
    local r = ls:run_to_steady{}
    local cpu = os.clock() - t0
    check(r.converged and r.verified, label .. ": not converged: " .. r.note)
    check(r.channel_frac_above <= 0.01, label .. ": channel cells above tol U")
    check(math.abs(r.volume_balance) <= tol, label .. ": volume balance")
    local off_text = "-"
    if case.K then
      local off, worst = off_slope(ls, case)
      off_text = ("%d (%.0e)"):format(off, worst)
      check(off == 0, ("%s: %d channel cells off the analytical slope (worst %.3g)"):format(
        label, off, worst))
      if size == sizes[#sizes] then -- the cells, and the line they should lie on
        local sa = ls:slope_area()
        local lo, hi = math.huge, 0
        for _, a in ipairs(sa.A) do lo, hi = math.min(lo, a), math.max(hi, a) end
        series[#series + 1] = { x = sa.A, y = sa.S, label = case.name .. ", channel cells",
                                marker = #series == 0 and "circle" or "open square" }
        local ax, ay = {}, {}
        for k = 0, 40 do
          ax[k + 1] = lo * (hi / lo) ^ (k / 40)
          ay[k + 1] = (U / case.K) ^ (1 / case.n) * ax[k + 1] ^ (-case.m / case.n)
        end
        series[#series + 1] = { x = ax, y = ay, style = "lines", rgb = "black",
                                dash = case.n ~= 1 and "dash" or nil,
                                label = ("S = (U/K)^{1/n} A^{-m/n}, n = %g"):format(case.n) }
      end
    end
    local after = 0
    for k = 1, 10 do
      local s = ls:step(1e4)
      after = math.max(after, s.channel_frac_above)
      check(s.channel_frac_above <= 0.01 and math.abs(s.volume_balance) <= tol,
            ("%s: implicit step %d leaves %.3g%% of the channel cells above tol U"):format(
              label, k, 100 * s.channel_frac_above))
    end
    print(("%-32s %7s %6d %7.2f %9d %9.2f%% %9.1e %10s %10.2f%%"):format(case.name,
          size .. "^2", r.steps, cpu, r.channel_cells, 100 * r.channel_frac_above,
          r.volume_balance, off_text, 100 * after))
  end
end
dfle.plot.xy{ path = opts.output .. "/steady_slope_area.png", series = series,
              xlog = true, ylog = true, xlabel = dfle.plot.label("A"), ylabel = dfle.plot.label("S"),
              title = ("Direct steady state from noise, %d^2 cells of 30 m: channel cells and the "
                       .. "analytical slope"):format(sizes[#sizes]) }
if #failures > 0 then
  error("not steady where it said so:\n  " .. table.concat(failures, "\n  "), 0)
end
print("every default steady state met the channel criterion, its volume balance and its "
      .. "fixed-point check")
