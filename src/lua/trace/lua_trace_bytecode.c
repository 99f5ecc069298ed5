/*
 * lua_trace_bytecode.c - the one thing a trace cannot see for itself.
 *
 * In Lua 5.4 `x == 0` with x a userdata is false without consulting any
 * metamethod, so a traced function that tests a flow field for equality
 * would silently take one branch for every node.  An assignment to an
 * upvalue (a counter) is a side effect the trace cannot intercept either.
 * Both show in the bytecode: the function is dumped (lua_dump) and its
 * instructions, and those of its nested functions, are scanned for EQ,
 * EQK, EQI and SETUPVAL.  The layout read is ldump.c's for Lua 5.4; a
 * chunk with another header is reported as unreadable, and the law then
 * runs as Lua.
 */
#include "lua/trace/lua_trace_internal.h"

#include <lauxlib.h>
#include <stdint.h>
#include <string.h>


/* Lua 5.4 opcodes the scan refuses (lopcodes.h order, stable in 5.4;
 * lua_trace_vm.c checks the running Lua compiles them so). */
enum { OP_SETUPVAL = 10, OP_EQ = 57, OP_EQK = 60, OP_EQI = 61 };

typedef struct { const unsigned char *p, *end; int bad; } reader;

static size_t rd_size(reader *r)
{
    size_t x = 0;
    for (int i = 0; i < 10; i++) {
        unsigned b;
        if (r->p >= r->end)
            break;
        b = *r->p++;
        x = (x << 7) | (b & 0x7f);
        if (b & 0x80)
            return x;
    }
    r->bad = 1;
    return 0;
}

static void rd_skip(reader *r, size_t n)
{
    if ((size_t)(r->end - r->p) < n) {
        r->bad = 1;
        r->p = r->end;
    } else {
        r->p += n;
    }
}

static void rd_string(reader *r)
{
    size_t n = rd_size(r);
    if (n > 0)
        rd_skip(r, n - 1);
}

/* One function of a binary chunk (ldump.c's layout) and its nested ones;
 * the opcodes of its own code (not the nested functions') go to ops
 * when it is not NULL (up to cap; *nops how many there are). */
static unsigned scan_function(reader *r, int depth, unsigned char *ops, size_t cap,
                              size_t *nops)
{
    unsigned found = 0;
    size_t n;
    if (depth > 64)
        return FOUND_BAD;
    rd_string(r); /* source */
    rd_size(r);   /* linedefined */
    rd_size(r);   /* lastlinedefined */
    rd_skip(r, 3); /* numparams, is_vararg, maxstacksize */
    n = rd_size(r);
    for (size_t i = 0; i < n && !r->bad; i++) {
        uint32_t ins;
        if (r->end - r->p < 4) {
            r->bad = 1;
            break;
        }
        memcpy(&ins, r->p, 4);
        r->p += 4;
        if (ops != NULL) {
            if (i < cap)
                ops[i] = (unsigned char)(ins & 0x7f);
            *nops = n;
        }
        switch (ins & 0x7f) {
        case OP_EQ: case OP_EQK: case OP_EQI: found |= FOUND_EQ; break;
        case OP_SETUPVAL: found |= FOUND_SETUPVAL; break;
        default: break;
        }
    }
    n = rd_size(r); /* constants */
    for (size_t i = 0; i < n && !r->bad; i++) {
        unsigned tag = r->p < r->end ? *r->p++ : (r->bad = 1, 0u);
        if (tag == 0x03 || tag == 0x13)
            rd_skip(r, 8);
        else if (tag == 0x04 || tag == 0x14)
            rd_string(r);
        else if (tag != 0x00 && tag != 0x01 && tag != 0x11)
            r->bad = 1;
    }
    rd_skip(r, 3 * rd_size(r)); /* upvalue descriptions */
    n = rd_size(r);             /* nested functions */
    for (size_t i = 0; i < n && !r->bad; i++)
        found |= scan_function(r, depth + 1, NULL, 0, NULL);
    rd_skip(r, rd_size(r)); /* line info */
    n = rd_size(r);         /* absolute line info */
    for (size_t i = 0; i < n && !r->bad; i++)
        rd_size(r), rd_size(r);
    n = rd_size(r); /* local variables */
    for (size_t i = 0; i < n && !r->bad; i++)
        rd_string(r), rd_size(r), rd_size(r);
    n = rd_size(r); /* upvalue names */
    for (size_t i = 0; i < n && !r->bad; i++)
        rd_string(r);
    return r->bad ? found | FOUND_BAD : found;
}

typedef struct { luaL_Buffer b; int init; } dump_state;

static int dump_writer(lua_State *L, const void *p, size_t sz, void *ud)
{
    dump_state *d = ud;
    if (!d->init) { /* after lua_dump has the function: the buffer may push */
        d->init = 1;
        luaL_buffinit(L, &d->b);
    }
    luaL_addlstring(&d->b, p, sz);
    return 0;
}

void dfle_trace_push_dump(lua_State *L, int fidx)
{
    dump_state d;
    d.init = 0;
    lua_pushvalue(L, fidx);
    lua_dump(L, dump_writer, &d, 0);
    if (!d.init) {
        lua_pop(L, 1);
        lua_pushnil(L);
        return;
    }
    luaL_pushresult(&d.b);
    lua_remove(L, -2);
}

/* The header of a chunk lua_dump wrote: Lua 5.4's signature, version,
 * format and data, 4-byte instructions, 8-byte integers and floats of
 * this machine's order.  0, with r past it, or -1 with why. */
static int read_header(reader *r, char *why, size_t why_len)
{
    static const unsigned char header[] = {0x1b, 'L', 'u', 'a', 0x54, 0x00, 0x19, 0x93,
                                           '\r', '\n', 0x1a, '\n', 4};
    const int64_t luac_int = 0x5678;
    const double luac_num = 370.5;
    if ((size_t)(r->end - r->p) < sizeof header + 2 + 16 + 1 ||
        memcmp(r->p, header, sizeof header) != 0) {
        size_t k = 0;
        while (r->p + k < r->end && k < sizeof header && r->p[k] == header[k])
            k++;
        snprintf(why, why_len, "its byte-code header differs from Lua 5.4.4's at byte %zu", k);
        return -1;
    }
    r->p += sizeof header;
    if (r->p[0] != 8 || r->p[1] != 8 || memcmp(r->p + 2, &luac_int, 8) != 0 ||
        memcmp(r->p + 10, &luac_num, 8) != 0) {
        snprintf(why, why_len, "its byte code has other integers or floats than the tracer "
                               "reads (sizes %d and %d)", r->p[0], r->p[1]);
        return -1;
    }
    r->p += 2 + 16 + 1; /* the sizes, LUAC_INT, LUAC_NUM, the main function's upvalues */
    return 0;
}

int dfle_trace_chunk_opcodes(const char *chunk, size_t len, unsigned char *ops, size_t cap,
                             size_t *nops, char *why, size_t why_len)
{
    reader r;
    r.p = (const unsigned char *)chunk;
    r.end = r.p + len;
    r.bad = 0;
    *nops = 0;
    if (read_header(&r, why, why_len) != 0)
        return -1;
    if (scan_function(&r, 0, ops, cap, nops) & FOUND_BAD) {
        snprintf(why, why_len, "its byte code has another layout than Lua 5.4.4's");
        return -1;
    }
    return 0;
}

unsigned dfle_trace_scan(lua_State *L, int fidx)
{
    reader r;
    size_t len;
    unsigned found;
    char why[8];

    dfle_trace_push_dump(L, fidx);
    if (lua_isnil(L, -1)) {
        lua_pop(L, 1);
        return FOUND_BAD;
    }
    r.p = (const unsigned char *)lua_tolstring(L, -1, &len);
    r.end = r.p + len;
    r.bad = 0;
    if (read_header(&r, why, sizeof why) != 0) {
        lua_pop(L, 1);
        return FOUND_BAD;
    }
    found = scan_function(&r, 0, NULL, 0, NULL);
    lua_pop(L, 1);
    return found;
}
