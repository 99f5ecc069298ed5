-- test_docs.lua - every runnable Lua block of README.md and doc/*.md runs
-- as written, so the docs stay true.
--
-- A block is a fenced ```lua block.  It runs on its own with dfle, in a
-- scratch directory, with DFLE_DATA_DIR set, and must exit 0 within the
-- time limit.  Two markers, on the line just above the fence, change that:
--
--   <!-- doc-test: continue -->      the block continues the page: it runs
--                                     after every runnable block above it
--                                     in the same file, as one script
--   <!-- doc-test: skip REASON -->   not run (a fragment, a sketch of a
--                                     long job); REASON must be given
--
-- A fenced ```python block marked "continue" reads the files the page's
-- Lua blocks above it wrote: those run as one script, then the block runs
-- in the same directory with Debian's /usr/bin/python3 (skipped, and said
-- so, when that has no xarray and netCDF4).  Other python blocks are not
-- run.
--
-- One test per block, named "FILE:LINE".
local T = ...
local tests = {}

-- Seconds per block: the docs' examples are small; under the sanitizers
-- (make check sets SANITIZE) code runs several times slower.
local LIMIT = (os.getenv("SANITIZE") or "") ~= "" and 300 or 60

local function doc_files()
    local files = { "README.md" }
    local h = io.popen("ls -1 " .. T.shquote(T.root .. "/doc") .. " 2>/dev/null")
    for name in h:lines() do
        if name:match("%.md$") then files[#files + 1] = "doc/" .. name end
    end
    h:close()
    return files
end

-- The blocks of one file: { line = n, code = text, skip = reason | nil }.
local function blocks_of(file)
    local text = assert(T.read_file(T.root .. "/" .. file), file)
    local blocks, lineno, prev, cur = {}, 0, "", nil
    for line in (text .. (text:sub(-1) == "\n" and "" or "\n")):gmatch("(.-)\n") do
        lineno = lineno + 1
        if cur then
            if line:match("^```%s*$") then
                blocks[#blocks + 1] = cur
                cur = nil
            else
                cur.code = cur.code .. line .. "\n"
            end
        elseif line:match("^```lua%s*$") or
               (line:match("^```python%s*$") and prev:match("^<!%-%- doc%-test:")) then
            local marker = prev:match("^<!%-%- doc%-test: (.-) %-%->%s*$")
            cur = { line = lineno, code = "", python = line:match("python") ~= nil }
            if cur.python and marker ~= "continue" then
                cur.bad_marker = (marker or prev) .. "' on a python block ('continue' is the only one"
            elseif marker == "continue" then
                cur.continues = true
            elseif marker and marker:match("^skip") then
                cur.skip = marker:match("^skip%s+(.+)$") or ""
            elseif marker then
                cur.bad_marker = marker
            end
        end
        prev = line
    end
    assert(cur == nil, file .. ": a ```lua block is not closed")
    return blocks
end

local PYTHON = "/usr/bin/python3"

local function run_block(file, block, code, python)
    local dir = T.tmpname()
    os.remove(dir)
    assert(os.execute("mkdir -p " .. T.shquote(dir)))
    local script = dir .. "/block.lua"
    T.write_file(script, code)
    local cmd = "cd " .. T.shquote(dir) .. " && timeout " .. LIMIT .. " " .. T.shquote(T.dfle) ..
                " -q block.lua 2>&1"
    if python then
        T.write_file(dir .. "/block.py", python)
        cmd = cmd .. " && timeout " .. LIMIT .. " " .. PYTHON .. " -W error::UserWarning block.py 2>&1"
    end
    local h = io.popen(cmd)
    local out = h:read("a")
    local ok, _, status = h:close()
    os.execute("rm -rf " .. T.shquote(dir))
    if not ok then
        error(string.format("%s:%d: the block %s (exit %s):\n%s", file, block.line,
                            status == 124 and ("ran over " .. LIMIT .. " s") or "fails",
                            tostring(status), out), 0)
    end
end

local counted = 0
for _, file in ipairs(doc_files()) do
    local code_so_far = nil
    for _, block in ipairs(blocks_of(file)) do
        local name = string.format("%s:%d", file, block.line)
        counted = counted + 1
        if block.bad_marker then
            tests[name] = function()
                error(name .. ": unknown doc-test marker '" .. block.bad_marker ..
                      (block.python and ")" or "' (continue, or skip with a reason)"), 0)
            end
        elseif block.skip then
            -- Skipped blocks still have to be Lua.
            tests[name .. " (parses; skipped: " .. block.skip .. ")"] = function()
                T.ok(block.skip ~= "", name .. ": a skipped block needs a reason")
                T.ok(load(block.code, "=" .. name), name .. " does not parse")
            end
        elseif block.python then
            local lua = code_so_far
            tests[name] = function()
                T.ok(lua ~= nil, name .. ": a python block with no Lua block before it")
                local _, has = T.sh(PYTHON .. " -c 'import xarray, netCDF4' 2>/dev/null")
                if not has then
                    print("skip - " .. name .. ": " .. PYTHON .. " has no xarray and netCDF4")
                    return
                end
                run_block(file, block, lua, block.code)
            end
        else
            local code
            if block.continues then
                T.ok(code_so_far ~= nil, name .. ": 'continue' with no runnable block before it")
                code = (code_so_far or "") .. block.code
            else
                code = block.code
            end
            code_so_far = (code_so_far or "") .. block.code
            tests[name] = function() run_block(file, block, code) end
        end
    end
end

tests["the docs have runnable Lua blocks"] = function()
    T.ok(counted >= 20, "found only " .. counted .. " ```lua blocks")
end

return tests
