/*
 * lua_args.c - dfle.args{...}: the command line of an experiment script,
 * and dfle.mkdir(path).
 *
 *   local o = dfle.args{
 *     usage   = "dfle examples/fig1_slope_area.lua [options] [output-directory]",
 *     about   = "The paper's Fig. 1 from a real DEM.",
 *     flags   = { quick = "a fast version (for the test suite)" },
 *     options = { data = { "DIR", "data directory (default: $DFLE_DATA_DIR)",
 *                          env = "DFLE_DATA_DIR",
 *                          needs = { "dem/srtm_bigtujunga30m_utm11.tif", "the DEM" } } },
 *     output  = true,   -- an output directory, default ".", created
 *   }
 *   o.quick, o.data, o.data_file, o.output
 *
 * Why in the binding: every example parsed its arguments by hand, so a
 * misspelt flag (--qiuck) or --help became the output directory and the
 * script failed after the whole run, and the directory was never made.
 * Here a script states its options once and gets, before any work is
 * done: --help (usage on stdout, exit 0), an error naming an unknown
 * option and listing the known ones, values for --name VALUE or
 * --name=VALUE, at most one positional argument, and the output
 * directory made (like mkdir -p), and a data file that is missing named
 * with the option and variable that point at it.  The parser is a few lines of Lua,
 * kept here as a chunk loaded when the module opens.
 */
#include "lua/core/dfle_lua.h"

#include <errno.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>

/* dfle.mkdir(path): make path and its parents (0777 less the umask);
 * an existing directory is fine.  Raises with the system's reason. */
static int l_mkdir(lua_State *L)
{
    const char *path = dfle_lua_check_string(L, 1, "mkdir", "the path");
    size_t len = strlen(path);
    char *buf;
    struct stat sb;

    if (len == 0)
        return luaL_error(L, "dfle.mkdir: the path is empty");
    buf = lua_newuserdatauv(L, len + 1, 0); /* collected if we raise */
    memcpy(buf, path, len + 1);
    /* Each prefix in turn, as mkdir -p does. */
    for (size_t k = 1; k <= len; k++) {
        if (buf[k] != '/' && buf[k] != '\0')
            continue;
        buf[k] = '\0';
        if (mkdir(buf, 0777) != 0 && errno != EEXIST)
            return luaL_error(L, "dfle.mkdir: cannot make '%s': %s", buf, strerror(errno));
        buf[k] = k < len ? '/' : '\0';
    }
    if (stat(path, &sb) != 0 || !S_ISDIR(sb.st_mode))
        return luaL_error(L, "dfle.mkdir: '%s' exists and is not a directory", path);
    lua_pushstring(L, path);
    return 1;
}

static const char args_chunk[] =
    "local spec, mkdir, mark_usage = ...\n"
    "if type(spec) ~= 'table' then error('dfle.args: expected a table {usage =, flags =, options =, output =}', 3) end\n"
    "for k in pairs(spec) do\n"
    "  if k ~= 'usage' and k ~= 'about' and k ~= 'flags' and k ~= 'options' and k ~= 'output' and k ~= 'arg' then\n"
    "    error(('dfle.args: unknown key %q (known: usage, about, flags, options, output, arg)'):format(tostring(k)), 3)\n"
    "  end\n"
    "end\n"
    "for _, k in ipairs{ 'usage', 'about' } do\n"
    "  if spec[k] ~= nil and type(spec[k]) ~= 'string' then error(('dfle.args: %s must be a string, got %s'):format(k, type(spec[k])), 3) end\n"
    "end\n"
    "for _, k in ipairs{ 'flags', 'options', 'arg' } do\n"
    "  if spec[k] ~= nil and type(spec[k]) ~= 'table' then error(('dfle.args: %s must be a table, got %s'):format(k, type(spec[k])), 3) end\n"
    "end\n"
    "for name, text in pairs(spec.flags or {}) do\n"
    "  if type(name) ~= 'string' or not name:match('^[%w_][%w_%-]*$') or type(text) ~= 'string' then\n"
    "    error(('dfle.args: flags are name = \\\"help text\\\" with names of letters, digits, _ and - (got %s = %s)'):format(type(name), type(text)), 3)\n"
    "  end\n"
    "end\n"
    "for name in pairs(spec.options or {}) do\n"
    "  if type(name) ~= 'string' or not name:match('^[%w_][%w_%-]*$') then\n"
    "    error(('dfle.args: option names are made of letters, digits, _ and - (got a %s)'):format(type(name)), 3)\n"
    "  end\n"
    "end\n"
    "for i = 1, spec.arg and #spec.arg or 0 do\n"
    "  local a = spec.arg[i]\n"
    "  if type(a) ~= 'string' then error(('dfle.args: arg[%d] must be a string, got %s'):format(i, type(a)), 3) end\n"
    "end\n"
    "local flags, options = spec.flags or {}, spec.options or {}\n"
    "local names = {}\n"
    "for name in pairs(flags) do names[#names + 1] = name end\n"
    "for name, o in pairs(options) do\n"
    "  if type(o) ~= 'table' or type(o[1]) ~= 'string' or type(o[2]) ~= 'string' then\n"
    "    error(('dfle.args: option %q must be {\\\"VALUE\\\", \\\"help text\\\", default = ..., env = ..., needs = ...}'):format(name), 3)\n"
    "  end\n"
    "  if o.env ~= nil and type(o.env) ~= 'string' then error(('dfle.args: option %q: env must be a string'):format(name), 3) end\n"
    "  if o.needs ~= nil and (type(o.needs) ~= 'table' or type(o.needs[1]) ~= 'string' or (o.needs[2] ~= nil and type(o.needs[2]) ~= 'string')) then\n"
    "    error(('dfle.args: option %q: needs must be {\\\"relative/file\\\", \\\"what it is\\\"}'):format(name), 3)\n"
    "  end\n"
    "  names[#names + 1] = name\n"
    "end\n"
    "table.sort(names)\n"
    "local function known()\n"
    "  local t = {}\n"
    "  for _, n in ipairs(names) do t[#t + 1] = '--' .. n .. (options[n] and (' ' .. options[n][1]) or '') end\n"
    "  t[#t + 1] = '--help'\n"
    "  return table.concat(t, ', ')\n"
    "end\n"
    "local function help()\n"
    "  local out = { 'usage: ' .. (spec.usage or 'dfle script.lua [options]') }\n"
    "  if spec.about then out[#out + 1] = ''; out[#out + 1] = spec.about end\n"
    "  out[#out + 1] = ''\n"
    "  out[#out + 1] = 'options:'\n"
    "  for _, n in ipairs(names) do\n"
    "    local left = '--' .. n .. (options[n] and (' ' .. options[n][1]) or '')\n"
    "    out[#out + 1] = ('  %-22s %s'):format(left, flags[n] or options[n][2])\n"
    "  end\n"
    "  out[#out + 1] = ('  %-22s %s'):format('--help', 'show this help and exit')\n"
    "  if spec.output then out[#out + 1] = ('  %-22s %s'):format('output-directory', 'where files go (default: the current directory; made if missing)') end\n"
    "  io.stdout:write(table.concat(out, '\\n'), '\\n')\n"
    "  os.exit(0)\n"
    "end\n"
    "-- a mistake on the command line: an error at the script's dfle.args\n"
    "-- line, marked so that dfle reports it as it does its own options\n"
    "-- (status 2, no traceback: the script is not at fault)\n"
    "local function usage_error(msg)\n"
    "  local at = debug.getinfo(4, 'Sl')\n"
    "  local where = at and at.currentline > 0 and (at.short_src .. ':' .. at.currentline .. ': ') or ''\n"
    "  error(mark_usage(where .. msg), 0)\n"
    "end\n"
    "local argv = spec.arg or _G.arg or {}\n"
    "local r = {}\n"
    "for n in pairs(flags) do r[n] = false end\n"
    "-- an empty default (an environment variable set to '') is no default\n"
    "for n, o in pairs(options) do\n"
    "  local d = o.default\n"
    "  if d == nil and o.env then d = os.getenv(o.env) end\n"
    "  if d ~= '' then r[n] = d end\n"
    "end\n"
    "local positional = {}\n"
    "local i = 1\n"
    "while i <= #argv do\n"
    "  local a = argv[i]\n"
    "  if a == '--help' or a == '-h' then help() end\n"
    "  local name, value = a:match('^%-%-([%w_%-]+)=(.*)$')\n"
    "  name = name or a:match('^%-%-([%w_%-]+)$')\n"
    "  if name then\n"
    "    if flags[name] then\n"
    "      if value then usage_error(('%s: --%s takes no value'):format(spec.usage or 'arguments', name)) end\n"
    "      r[name] = true\n"
    "    elseif options[name] then\n"
    "      if not value then\n"
    "        i = i + 1\n"
    "        value = argv[i]\n"
    "        if value == nil then usage_error(('--%s needs a value (%s)'):format(name, options[name][1])) end\n"
    "      end\n"
    "      r[name] = value\n"
    "    else\n"
    "      usage_error(('unknown option %q (options: %s)'):format(a, known()))\n"
    "    end\n"
    "  elseif a:sub(1, 1) == '-' and a ~= '-' then\n"
    "    usage_error(('unknown option %q (options: %s)'):format(a, known()))\n"
    "  else\n"
    "    positional[#positional + 1] = a\n"
    "  end\n"
    "  i = i + 1\n"
    "end\n"
    "if spec.output then\n"
    "  if #positional > 1 then usage_error(('one output directory at most (got %q and %q)'):format(positional[1], positional[2])) end\n"
    "  r.output = positional[1] or '.'\n"
    "  local ok, e = pcall(mkdir, r.output)\n"
    "  if not ok then usage_error((tostring(e):gsub('^dfle%.args:%d+: ', ''))) end\n"
    "elseif #positional > 0 then\n"
    "  usage_error(('unexpected argument %q (options: %s)'):format(positional[1], known()))\n"
    "end\n"
    "-- needs: a directory option that must hold a file; without it, say\n"
    "-- what is needed and how to point at it, and stop (status 2)\n"
    "for _, n in ipairs(names) do\n"
    "  local o = options[n]\n"
    "  if o and o.needs then\n"
    "    local file = r[n] and (r[n] .. '/' .. o.needs[1])\n"
    "    local probe = file and io.open(file, 'rb')\n"
    "    if not probe then\n"
    "      local top = o.needs[1]:match('^([^/]+/)') or o.needs[1]\n"
    "      io.stderr:write(('%s: needs %s%s: pass --%s %s%s to the directory holding %s%s\\n'):format(\n"
    "        argv[0] or 'script', o.needs[2] and (o.needs[2] .. ', ') or '', o.needs[1], n, o[1],\n"
    "        o.env and (' or set ' .. o.env) or '', top, r[n] and (' (not in ' .. r[n] .. ')') or ''))\n"
    "      os.exit(2)\n"
    "    end\n"
    "    probe:close()\n"
    "    r[n .. '_file'] = file\n"
    "  end\n"
    "end\n"
    "return r\n";

/* The last command-line mistake dfle.args raised, in the registry. */
static const char usage_key = 'u';

/* mark_usage(msg) -> msg, remembered as a command-line mistake. */
static int l_mark_usage(lua_State *L)
{
    luaL_checkstring(L, 1);
    lua_settop(L, 1);
    lua_pushvalue(L, 1);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &usage_key);
    return 1;
}

int dfle_lua_is_usage_error(lua_State *L, const char *msg)
{
    int same;
    if (msg == NULL)
        return 0;
    lua_rawgetp(L, LUA_REGISTRYINDEX, &usage_key);
    /* the very message: one the script caught long ago is not this */
    same = lua_type(L, -1) == LUA_TSTRING && strcmp(lua_tostring(L, -1), msg) == 0;
    lua_pop(L, 1);
    return same;
}

/* dfle.args(spec): the chunk, called with the spec, dfle.mkdir and
 * mark_usage. */
static int l_args(lua_State *L)
{
    lua_settop(L, 1);
    lua_pushvalue(L, lua_upvalueindex(1));
    lua_insert(L, 1);
    lua_pushcfunction(L, l_mkdir);
    lua_pushcfunction(L, l_mark_usage);
    lua_call(L, 3, 1);
    return 1;
}

void dfle_lua_open_args(lua_State *L)
{
    if (luaL_loadbufferx(L, args_chunk, sizeof args_chunk - 1, "=dfle.args", "t") != LUA_OK)
        lua_error(L); /* only out of memory: the source is ours */
    lua_pushcclosure(L, l_args, 1);
    lua_setfield(L, -2, "args");
    lua_pushcfunction(L, l_mkdir);
    lua_setfield(L, -2, "mkdir");
}
