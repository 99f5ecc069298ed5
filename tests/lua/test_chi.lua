-- test_chi.lua - dfle.chi and dfle.concavity from Lua: steady states of
-- the stream-power law (a model channel, a landscape) against
-- k_s = (U/K)^(1/n) and theta = m/n, DEM networks, tables, the CSV
-- file, the figures, and the errors.
local T = ...
local tests = {}

local TIF = T.data .. "/dem/srtm_bigtujunga30m_utm11.tif"
local BLACK = { 396887, 3799338 }

local function raises(fn, ...)
  local msg = T.raises_here(fn, ...)
  T.match(msg, "test_chi%.lua:%d+:")
  return msg
end

-- A channel at steady state under U = K A^m S^n alone.
local function steady_channel(K, m, n, U)
  local fl = dfle.fluvial.stream_power{ K = K, m = m, n = n }
  local mdl = dfle.model{ channel = dfle.channel{ A_max = 2e6, dx = 10 }, U = U, fluvial = fl,
                          router = false }
  local z = {}
  for i = 1, mdl.n do z[i] = (mdl.n - i) * 2 end
  mdl:set_z(z)
  T.ok(mdl:run_to_steady{ tol = 1e-9 }.converged, "steady")
  return mdl
end

tests["a steady channel lies on one chi-z line of slope (U/K)^(1/n)"] = function()
  for _, case in ipairs{ { K = 1e-5, m = 0.45, n = 1 }, { K = 2e-6, m = 1.0, n = 2 } } do
    local U = 1e-3
    local ks, theta = (U / case.K) ^ (1 / case.n), case.m / case.n
    local mdl = steady_channel(case.K, case.m, case.n, U)
    local c = dfle.chi(mdl, { theta_ref = theta })
    T.eq(c.kind, "model")
    T.eq(c.n, mdl.n)
    T.eq(c.n_base, 1)
    T.close(c.k_sn, ks, 1e-6, 0, "k_sn of the line")
    T.close(c.M_chi, ks, 1e-6, 0, "A0 = 1 m^2: M_chi = k_sn")
    T.ok(c.r2 > 1 - 1e-9, "R^2 " .. c.r2)
    local k, S, A = c:get("k_sn"), mdl:get("S"), mdl:get("A")
    for i = 1, mdl.n - 1, 17 do
      T.close(k[i], ks, 1e-6, 0, "k_sn at node " .. i)
      T.close(k[i], S[i] * A[i] ^ theta, 1e-9, 0, "k_sn = S A^theta at node " .. i)
    end
    -- A0 = 1e6 m^2: the line's slope is k_sn A0^-theta
    local c6 = dfle.chi(mdl, { theta_ref = theta, A0 = 1e6 })
    T.close(c6.M_chi, ks * 1e6 ^ -theta, 1e-6, 0, "M_chi with A0")
    T.close(c6.k_sn, ks, 1e-6, 0, "k_sn with A0")
    -- the concavity, by both methods
    local kc = assert(dfle.concavity(mdl, { method = "chi" }))
    T.close(kc.theta, theta, 0, 2e-4, "chi concavity")
    T.close(kc.k_s, ks, 2e-3, 0, "chi k_s")
    T.eq(kc.at_bound, false)
    T.eq(#kc.curve.theta, #kc.curve.r2)
    local ks_ = assert(dfle.concavity(mdl, { method = "slope_area" }))
    T.close(ks_.theta, theta, 0, 1e-4, "slope-area concavity")
    T.close(ks_.k_s, ks, 1e-3, 0, "slope-area k_s")
  end
end

tests["a steady landscape: k_sn = S A^theta on its channels, one chi-z line"] = function()
  local K, U = 1e-4, 1e-3
  local fl = dfle.fluvial.stream_power{ K = K, m = 0.5, n = 1 }
  local ls = dfle.landscape{ nx = 30, ny = 24, dx = 30, fluvial = fl, router = false,
                             U = U, A0 = 4 * 900, noise = { seed = 5 } }
  T.ok(ls:run_to_steady{}.converged)
  local c = dfle.chi(ls, { theta_ref = 0.5 })
  T.eq(c.kind, "landscape")
  T.eq(c.n, ls.data_cells)
  T.close(c.A_min, 4 * 900, 1e-12, 0, "A_min: the channel cells")
  -- the steady criterion holds slopes to about 0.5 % (test_landscape.lua)
  T.close(c.k_sn, (U / K), 5e-3, 0, "k_sn of the line")
  T.ok(c.r2 > 0.9999, "R^2 " .. c.r2)
  local k, A, S, E, N = c:get("k_sn"), c:get("A"), c:get("S"), c:get("E"), c:get("N")
  local z, zl = c:get("z"), ls:get("z")
  local seen = 0
  for i = 1, c.n do
    if k[i] == k[i] then
      T.close(k[i], S[i] * A[i] ^ 0.5, 1e-9, 0, "k_sn = S A^theta at cell " .. i)
      seen = seen + 1
    end
  end
  T.ok(seen > 50, "channel cells with k_sn: " .. seen)
  -- cells in row-major order, centres in map coordinates
  T.close(E[1], ls.x0 + 15, 1e-12, 0)
  T.close(N[1], ls.y0 - 15, 1e-12, 0)
  T.close(z[1], zl[1], 0, 0)
  local kc = assert(dfle.concavity(ls))
  T.close(kc.theta, 0.5, 0, 0.01, "chi concavity of the landscape")
  T.eq(kc.A_min, 4 * 900)
end

tests["a DEM network: chi, k_sn over a window, CSV with its record"] = function()
  local dem = dfle.dem.read(TIF)
  dem:fill()
  local net = dem:network{ A_min = 1e5, outlet = BLACK }
  local c = dfle.chi(net, { A_min = 1e6 })
  T.eq(c.kind, "network")
  T.close(c.theta_ref, 0.45, 0, 0)
  T.close(c.window, net.ds, 0, 0, "window: the network's slope interval")
  T.eq(c.n, net.n)
  T.ok(c.n_fit > 100 and c.n_fit < c.n, "cells fitted " .. c.n_fit)
  T.ok(c.k_sn > 10 and c.k_sn < 500, "k_sn " .. c.k_sn)
  T.ok(c.r2 > 0.9, "R^2 " .. c.r2)
  local chi, rcv, d, A, k = c:get("chi"), c:get("receiver"), c:get("d"), c:get("A"), c:get("k_sn")
  T.bits_equal(d, net:get("d"), "d")
  for i = 1, c.n do
    if rcv[i] == 0 then
      T.eq(chi[i], 0)
    else
      -- each link with its upper cell's area
      T.close(chi[i] - chi[rcv[i]], (d[i] - d[rcv[i]]) * A[i] ^ -0.45, 1e-9, 1e-12, "link " .. i)
    end
    T.ok((k[i] == k[i]) == (A[i] >= 1e6), "k_sn only where A >= A_min: cell " .. i)
  end
  local path = T.tmpname(".csv")
  c:write_csv(path)
  local text = T.read_file(path)
  T.has(text, "# units: E=m, N=m, x=m, d=m, z=m, A=m^2, S=-, chi=m, k_sn=m^0.9, z_base=m",
        "E,N,x,d,z,A,S,chi,k_sn,z_base,receiver", "chi Perron and Royden 2013:",
        "theta_ref=0.45", "A_min=1000000 m^2", "k_sn=", "m^0.9", "given_E=396887 m")
  local rows = 0
  for _ in text:gmatch("\n[%d%-]") do rows = rows + 1 end
  T.eq(rows, c.n)
  T.has(T.read_file(path:sub(1, -5) .. ".json"), '"theta_ref": 0.45')
  -- slope-area concavity of the same network's fluvial reach
  local k2 = assert(dfle.concavity(net, { method = "slope_area", A_min = 1e6 }))
  T.ok(k2.theta > 0.2 and k2.theta < 1, "theta " .. k2.theta)
  T.eq(k2.nbins, 100)
end

tests["a table: a chain of cells, receivers 1-based, lengths or distances"] = function()
  -- S = 100 A^-0.45 exactly, by links
  local A, z, rcv, len, d = {}, {}, {}, {}, {}
  local n = 50
  for i = 1, n do A[i] = 1e4 * i end
  z[n], d[n] = 0, 0
  for i = n - 1, 1, -1 do
    z[i] = z[i + 1] + 30 * 100 * A[i] ^ -0.45
    d[i] = d[i + 1] + 30
  end
  for i = 1, n do rcv[i], len[i] = i < n and i + 1 or 0, 30 end
  local a = dfle.chi{ z = z, A = A, receiver = rcv, length = len }
  local b = dfle.chi{ z = z, A = A, receiver = rcv, d = d }
  T.close(a.k_sn, 100, 1e-12, 0)
  T.close(b.k_sn, 100, 1e-12, 0)
  T.eq(a.kind, "table")
  T.eq(a:get("receiver")[1], 2)
  T.eq(a:get("receiver")[n], 0)
  raises(function() return a:get("E") end, "has no 'E'")
  T.has(tostring(a), "dfle.chi(table, 50 cells")
  -- the concavity of a range that excludes it: its end, flagged, warned
  local out, ok = T.run_dfle(([[
    local A, z, rcv, len = {}, {}, {}, {}
    for i = 1, 50 do A[i] = 1e4 * i; rcv[i] = i < 50 and i + 1 or 0; len[i] = 30 end
    z[50] = 0
    for i = 49, 1, -1 do z[i] = z[i + 1] + 3000 * A[i] ^ -0.45 end
    local k = dfle.concavity({ z = z, A = A, receiver = rcv, length = len }, { range = { 0.1, 0.3 } })
    print(k.at_bound, k.theta, k.note)
  ]]))
  T.ok(ok, out)
  T.has(out, "dfle: warning: ", "dfle.concavity: the most collinear theta is the end of the range",
        "true\t0.3")
end

tests["figures: chi-z, slope-area beside it, and k_sn maps"] = function()
  local dem = dfle.dem.read(TIF)
  dem:fill()
  local net = dem:network{ A_min = 1e5, outlet = BLACK }
  local c = dfle.chi(net, { A_min = 1e6, window = 300 })
  for _, f in ipairs{
    function(p) dfle.plot.chi(c, p) end,
    function(p) dfle.plot.slope_area_chi(net, c, p, nil, { title = "t" }) end,
    function(p) dfle.plot.ksn_map(c, p, { dem = dem, clabel = "k" }) end,
  } do
    local p = T.tmpname(".png")
    f(p)
    local png = T.read_file(p)
    T.ok(png and png:sub(2, 4) == "PNG", "a PNG")
  end
  -- a map needs relief: the DEM for a network, a landscape its own
  raises(function() dfle.plot.ksn_map(c, T.tmpname(".png")) end, "give dem = the DEM")
  local ls = dfle.landscape{ nx = 20, ny = 16, dx = 30, router = false, U = 1e-3, A0 = 3600,
                             fluvial = dfle.fluvial.stream_power{ K = 1e-4, m = 0.5, n = 1 },
                             noise = { seed = 3 } }
  ls:run_to_steady{}
  dfle.plot.ksn_map(dfle.chi(ls), T.tmpname(".png"))
  local mdl = steady_channel(1e-5, 0.45, 1, 1e-3)
  local cm = dfle.chi(mdl)
  raises(function() dfle.plot.ksn_map(cm, T.tmpname(".png")) end, "no map coordinates")
  local other = dfle.dem.read(T.data .. "/dem/hugo_site_filled.asc", { nodata = -9999 })
  raises(function() dfle.plot.ksn_map(c, T.tmpname(".png"), { dem = other }) end,
         "outside the DEM given")
end

tests["errors name the parameter"] = function()
  local chain = { z = { 2, 1, 0 }, A = { 1, 2, 3 }, receiver = { 2, 3, 0 }, length = { 1, 1, 0 } }
  raises(function() return dfle.chi(42) end, "expected a dfle.profile")
  raises(function() return dfle.chi(chain, { theta = 0.5 }) end, "theta")
  raises(function() return dfle.chi(chain, { theta_ref = -1 }) end, "theta_ref must be in 0..5")
  raises(function() return dfle.chi(chain, { A0 = 0 }) end, "A0 must be")
  raises(function() return dfle.chi{ z = { 1 }, A = { 1 } } end, "needs 'receiver'")
  raises(function() return dfle.chi{ z = { 1, 0 }, A = { 1, 2 }, receiver = { 2, 0 } } end,
         "'length'")
  raises(function() return dfle.chi{ z = { 1, 0 }, A = { 1, 2 }, receiver = { 3, 0 }, length = { 1, 1 } } end,
         "receiver[1] must be the 1-based index")
  raises(function() return dfle.chi{ z = { 1, 0 }, A = { 1, 2 }, receiver = { 2, 0 }, length = { 0, 1 } } end,
         "cell 1 drains to cell 2 over 0")
  raises(function() return dfle.chi{ z = { 1, 0, 0 }, A = { 1, 2, 3 }, receiver = { 2, 1, 0 }, length = { 1, 1, 1 } } end,
         "cycle")
  raises(function() return dfle.chi(chain, { A_min = 1e9 }) end, "too few for the chi-z line")
  raises(function() return dfle.concavity(chain, { method = "linear" }) end, "method must be")
  raises(function() return dfle.concavity(chain, { range = { 0.5 } }) end, "'range' must be {lo, hi}")
  local k, why = dfle.concavity(chain, { A_min = 2.5 })
  T.eq(k, nil)
  T.match(why, "too few for the chi%-z line")
end

return tests
