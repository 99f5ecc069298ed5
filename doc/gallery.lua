-- gallery.lua - every figure the examples draw, at once.
--
-- doc/figures.md lists each figure with the script that draws it and
-- what it shows.  This script runs every example in its quick mode, one
-- output directory each, checks the figures against that list (each one
-- listed was drawn, none was drawn that is not listed), and writes
--   index.md            the list with the images, by script
--   contact_sheet.png   every figure on one page
--
--   dfle doc/gallery.lua [output-directory]     (default build/figures)
--   dfle doc/gallery.lua --check DIR
--
-- --check draws nothing: it compares the PNG files in DIR (where the
-- test suite ran every example) with the list, so the list cannot fall
-- behind the examples.  The DEM examples need DFLE_DATA_DIR.

local opts = dfle.args{
  usage = "dfle doc/gallery.lua [options] [output-directory]",
  about = "Render every example's figures in quick mode; write index.md and contact_sheet.png.",
  options = { check = { "DIR", "draw nothing: check the figures in DIR against doc/figures.md" } },
  output = true,
}

local here = arg[0]:match("^(.*)/[^/]*$") or "."
local root = here .. "/.."
local function shquote(s) return "'" .. s:gsub("'", "'\\''") .. "'" end
local function lines_of(cmd)
  local h, out = io.popen(cmd), {}
  for l in h:lines() do out[#out + 1] = l end
  h:close()
  return out
end

-- The catalogue: rows "| `file.png` | `examples/x.lua` | caption |".
local figures, by_file, scripts, by_script = {}, {}, {}, {}
for line in io.lines(here .. "/figures.md") do
  local file, script, caption = line:match("^| `([^`]+%.png)` | `(examples/[%w_]+%.lua)` | (.*) |$")
  if file then
    if by_file[file] then error(("doc/figures.md lists %s twice"):format(file)) end
    local f = { file = file, script = script, caption = caption,
                full_only = caption:find("^%*Full run only%*") ~= nil }
    figures[#figures + 1], by_file[file] = f, f
    if not by_script[script] then
      by_script[script] = {}
      scripts[#scripts + 1] = script
    end
    table.insert(by_script[script], f)
  end
end
if #figures == 0 then error("doc/figures.md lists no figures: its table changed shape?") end

local problems = {}
local function problem(fmt, ...) problems[#problems + 1] = fmt:format(...) end

-- Every example is in the catalogue (a new one must say what it draws).
for _, path in ipairs(lines_of("ls " .. shquote(root .. "/examples"))) do
  local script = "examples/" .. path
  if path:match("%.lua$") and not by_script[script] then
    problem("%s draws figures doc/figures.md does not list (add its rows)", script)
  end
end

-- Drawn (file -> directory) against listed.
local function compare(drawn)
  for _, f in ipairs(figures) do
    if not drawn[f.file] and not f.full_only then
      problem("%s (%s) was not drawn", f.file, f.script)
    end
  end
  for file, dir in pairs(drawn) do
    if not by_file[file] then problem("%s/%s is not listed in doc/figures.md", dir, file) end
  end
end

local function pngs(dir, into)
  for _, name in ipairs(lines_of("ls " .. shquote(dir) .. " 2>/dev/null")) do
    if name:match("%.png$") and name ~= "contact_sheet.png" then into[name] = dir end
  end
end

local function finish()
  if #problems > 0 then
    io.stderr:write("gallery: ", table.concat(problems, "\ngallery: "), "\n")
    os.exit(1)
  end
end

if opts.check then
  local drawn = {}
  pngs(opts.check, drawn)
  compare(drawn)
  finish()
  print(("gallery: the figures drawn match the %d doc/figures.md lists"):format(#figures))
  return
end

-- The dfle command running this script runs the examples too.
local k = -1
while arg[k - 1] do k = k - 1 end
local dfle_cmd = arg[k]
local out = opts.output == "." and "build/figures" or opts.output
dfle.mkdir(out)

if not os.getenv("DFLE_DATA_DIR") then
  print("gallery: DFLE_DATA_DIR is not set: the DEM examples will draw nothing")
end
local drawn, t_all = {}, os.time()
for _, script in ipairs(scripts) do
  local name = script:match("([%w_]+)%.lua$")
  local dir = out .. "/" .. name
  -- a directory of an earlier gallery run is replaced (the examples
  -- resume from files they find); anything else is left alone
  local marker = io.open(dir .. "/.gallery")
  if marker then
    marker:close()
    os.execute("rm -rf " .. shquote(dir))
  elseif io.open(dir) then
    error(("%s exists and was not made by the gallery: choose another output directory"):format(dir))
  end
  dfle.mkdir(dir)
  io.open(dir .. "/.gallery", "w"):close()
  local t0 = os.time()
  local ok = os.execute(("%s -q %s --quick %s > %s 2>&1"):format(shquote(dfle_cmd),
                        shquote(root .. "/" .. script), shquote(dir), shquote(dir .. "/run.log")))
  print(("%-36s %s, %d s"):format(script, ok and "ok" or "FAILED", os.time() - t0))
  if not ok then
    problem("%s failed (see %s/run.log)%s", script, dir,
            os.getenv("DFLE_DATA_DIR") and "" or "; the DEM examples need DFLE_DATA_DIR")
  end
  pngs(dir, drawn)
end
compare(drawn)

-- index.md: the catalogue with its images.
local index = assert(io.open(out .. "/index.md", "w"))
index:write("# dfle figures (quick mode)\n\nDrawn by `dfle doc/gallery.lua` from the examples' ",
            "quick runs; captions from doc/figures.md. ",
            "[All on one page](contact_sheet.png).\n")
local images = {}
for _, script in ipairs(scripts) do
  index:write(("\n## %s\n"):format(script))
  for _, f in ipairs(by_script[script]) do
    local dir = drawn[f.file]
    index:write(("\n### %s\n\n%s\n"):format(f.file, f.caption))
    if dir then
      local rel = dir:sub(#out + 2) .. "/" .. f.file
      index:write(("\n![%s](%s)\n"):format(f.file, rel))
      images[#images + 1] = dir .. "/" .. f.file
    end
  end
end
index:close()
if #images > 0 then
  -- titled by their file names, shown as they are (not as enhanced text)
  dfle.plot.sheet{ path = out .. "/contact_sheet.png", images = images,
                   columns = 4, dpi = 100 }
end
print(("wrote %s/index.md and %s/contact_sheet.png: %d figures in %d s")
      :format(out, out, #images, os.time() - t_all))
finish()
