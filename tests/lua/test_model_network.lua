-- test_model_network.lua - dfle.model on a DEM's channel network
-- (dem:network{...}): every cell a node draining to its receiver, the
-- debris flows of every channel head, the model started from the DEM.
local T = ...
local tests = {}

local TIF = T.data .. "/dem/srtm_bigtujunga30m_utm11.tif"
local BLACK = { 396887, 3799338 }

local net_cache
local function network()
  if not net_cache then
    local dem = dfle.dem.read(TIF)
    dem:fill()
    net_cache = dem:network{ A_min = 2e5, outlet = BLACK }
  end
  return net_cache
end

tests["a model on a DEM network: its cells, areas and elevations"] = function()
  local net = network()
  local m = dfle.model{ network = net, router = false }
  T.eq(m.n, net.n)
  local z, A = m:get("z"), m:get("A")
  local nz, nA = net:get("z"), net:get("A")
  for i = 1, net.n do
    T.eq(z[i], nz[i])
    T.eq(A[i], nA[i])
  end
  -- widths k_w A^b, as a channel's
  local m2 = dfle.model{ network = net, router = false, k_w = 0.1, b = 0.5 }
  local w = m2:get("w")
  T.close(w[1], 0.1 * nA[1] ^ 0.5, 1e-12)
end

tests["rivers alone on a DEM network: the analytical steady slopes"] = function()
  local net = network()
  local K, mm, U = 1e-5, 0.45, 5e-4
  local m = dfle.model{ network = net, router = false, U = U,
                        fluvial = dfle.fluvial.stream_power{ K = K, m = mm, n = 1 } }
  local r = m:run_to_steady{}
  T.ok(r.converged, r.note)
  -- at steady state every non-outlet cell has U = K A^m S
  local S, A, rcv = m:get("S"), m:get("A"), net:get("receiver")
  local checked = 0
  for i = 1, m.n do
    if rcv[i] ~= 0 then
      T.close(S[i], U / (K * A[i] ^ mm), 1e-6)
      checked = checked + 1
    end
  end
  T.ok(checked > 10, checked .. " cells")
end

tests["the process router on a DEM network: one flow from every head"] = function()
  local net = network()
  local rt = dfle.router.process{}
  local m = dfle.model{ network = net, router = rt, law = dfle.law.power{}, combine = "count" }
  -- the DEM's relief three times over: on its own 30 m cells most piles
  -- of 200 m^3 at the heads are held by friction (a flow at rest at once)
  local z = net:get("z")
  for i = 1, #z do z[i] = 3 * z[i] end
  m:set_z(z)
  local rep = rt:route(m)
  local rcv, heads = net:get("receiver"), 0
  local donors = {}
  for i = 1, net.n do if rcv[i] ~= 0 then donors[rcv[i]] = true end end
  for i = 1, net.n do if not donors[i] then heads = heads + 1 end end
  T.eq(rep.heads, heads)
  T.ok(heads > 1, heads .. " heads")
  T.eq(rep.heads_routed, heads)
  T.ok(rep.volume_error < 1e-12, "volume error " .. rep.volume_error)
  T.ok(rep.steps > 2 * heads, "the flows moved: " .. rep.steps .. " steps")
  -- Theta = 1 where a flow erodes; there E_df > 0 wherever the DEM
  -- slopes (a filled flat has none)
  local Theta, Edf, S = m:get("Theta"), m:get("E_df"), m:get("S")
  local reached = 0
  for i = 1, net.n do
    if Theta[i] > 0 then
      reached = reached + 1
      if S[i] > 0 then T.ok(Edf[i] > 0, "E_df > 0 where reached") end
    else
      T.eq(Edf[i], 0)
    end
  end
  T.ok(reached >= heads, reached .. " cells reached")
end

tests["a model on a DEM network: wrong options are named"] = function()
  local net = network()
  T.raises_here(function() return dfle.model{ network = {} } end,
                "parameter 'network' must be a dfle.profile")
  T.raises_here(function() return dfle.model{ network = net, channel = dfle.channel{} } end,
                "give 'channel' or 'network', not both")
  T.raises_here(function() return dfle.model{ k_w = 0.1 } end, "'k_w' is for a DEM network")
  T.raises_here(function() return dfle.model{ combine = "count" } end, "'combine' is for a network")
  T.raises_here(function() return dfle.model{ network = net, k_w = -1 } end, "k_w must be > 0")
  T.raises_here(function() return dfle.model{ network = net, combine = "all" } end, "invalid option 'all'")
end

return tests
