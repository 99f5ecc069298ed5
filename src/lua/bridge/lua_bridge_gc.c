/*
 * lua_bridge_gc.c - which host callbacks only the host's references keep
 * alive (lua_bridge.h: dfle_bridge_owned_callbacks), so that the host's
 * collector can see a cycle that goes through Lua: a Python function
 * that refers to the landscape whose U(x, y) it is.
 *
 * The walk marks what Lua's roots reach (the registry but the host's
 * own references, the main thread's stack): that is alive whatever the
 * host does.  Then, from each host reference, what it reaches beyond
 * that: a callback found so is owned by the references that reach it,
 * and goes when the last of them goes.  One that Lua's roots reach is
 * owned by none (the host keeps it: a leak at worst, never a callable
 * freed while Lua may call it).  What Lua's API cannot see is not
 * guessed at: a suspended coroutine (its frames below the top) makes
 * the walk give up; a thread that only stores values (a law keeps its
 * functions on one) is read whole.  The binding's references to a landscape's callbacks,
 * held in the registry by the C object, are taken as the landscape's.
 */
#include <lauxlib.h>

#include "lua/objects/lua_landscape.h"

#include "lua/bridge/lua_bridge_internal.h"

typedef struct walk {
    lua_State *L;
    int marks;          /* value -> true: met in this walk              */
    int work;           /* values to expand, 1..n                       */
    lua_Integer n;
    int live;           /* values not to enter (alive anyway), or 0     */
    int owned;          /* registry key -> true: a landscape's          */
    int record_owned;   /* fill `owned` while walking                   */
    int hosts;          /* host callback -> the set of its owners, or 0 */
    lua_Integer owner;
    int gave_up;
} walk;

/* The value on top, to be expanded unless met already; popped. */
static void offer(walk *w)
{
    lua_State *L = w->L;
    int t = lua_type(L, -1);
    if (t == LUA_TTHREAD && lua_tothread(L, -1) == L) {
        lua_pop(L, 1); /* the main thread: its stack is a root already */
        return;
    }
    if (t != LUA_TTABLE && t != LUA_TFUNCTION && t != LUA_TUSERDATA && t != LUA_TTHREAD) {
        lua_pop(L, 1);
        return;
    }
    if (w->live != 0) {
        lua_pushvalue(L, -1);
        if (lua_rawget(L, w->live) != LUA_TNIL) {
            lua_pop(L, 2);
            return;
        }
        lua_pop(L, 1);
    }
    lua_pushvalue(L, -1);
    if (lua_rawget(L, w->marks) != LUA_TNIL) {
        lua_pop(L, 2);
        return;
    }
    lua_pop(L, 1);
    lua_pushvalue(L, -1);
    lua_pushboolean(L, 1);
    lua_rawset(L, w->marks);
    lua_rawseti(L, w->work, ++w->n);
}

static void offer_ref(walk *w, int ref)
{
    if (ref <= 0)
        return;
    lua_rawgeti(w->L, LUA_REGISTRYINDEX, ref);
    offer(w);
    if (w->record_owned) {
        lua_pushboolean(w->L, 1);
        lua_rawseti(w->L, w->owned, ref);
    }
}

static void expand_userdata(walk *w, int v)
{
    lua_State *L = w->L;
    const lua_ls *u;
    for (int i = 1; lua_getiuservalue(L, v, i) != LUA_TNONE; i++)
        offer(w);
    lua_pop(L, 1);
    if ((u = luaL_testudata(L, v, DFLE_LUA_LANDSCAPE)) != NULL) {
        for (int k = 0; k < F_COUNT; k++)
            offer_ref(w, u->cb[k].ref);
        offer_ref(w, u->ref_combine);
    } else if (w->hosts != 0 && luaL_testudata(L, v, DFLE_BRIDGE_HOST_FN) != NULL) {
        /* hosts[H][owner] = true */
        lua_pushvalue(L, v);
        if (lua_rawget(L, w->hosts) == LUA_TNIL) {
            lua_pop(L, 1);
            lua_newtable(L);
            lua_pushvalue(L, v);
            lua_pushvalue(L, -2);
            lua_rawset(L, w->hosts);
        }
        lua_pushboolean(L, 1);
        lua_rawseti(L, -2, w->owner);
        lua_pop(L, 1);
    }
}

/* A thread that only stores values (a law keeps its functions on one):
 * its whole stack is in view.  One with a call in it (a suspended
 * coroutine) shows only its top frame: the walk gives up. */
static void expand_thread(walk *w, int v)
{
    lua_State *L = w->L, *T = lua_tothread(L, v);
    lua_Debug ar;
    if (lua_status(T) != LUA_OK || lua_getstack(T, 0, &ar)) {
        w->gave_up = 1;
        return;
    }
    for (int i = 1, n = lua_gettop(T); i <= n; i++) {
        if (!lua_checkstack(T, 1)) {
            w->gave_up = 1;
            return;
        }
        lua_pushvalue(T, i);
        lua_xmove(T, L, 1);
        offer(w);
    }
}

/* Everything the marked values reach. */
static void run(walk *w)
{
    lua_State *L = w->L;
    while (w->n > 0 && !w->gave_up) {
        int v;
        lua_rawgeti(L, w->work, w->n);
        lua_pushnil(L);
        lua_rawseti(L, w->work, w->n--);
        v = lua_gettop(L);
        if (lua_getmetatable(L, v))
            offer(w);
        switch (lua_type(L, v)) {
        case LUA_TTABLE:
            lua_pushnil(L);
            while (lua_next(L, v)) {
                offer(w);               /* the value */
                lua_pushvalue(L, -1);
                offer(w);               /* the key, kept for lua_next */
            }
            break;
        case LUA_TFUNCTION:
            for (int i = 1; lua_getupvalue(L, v, i) != NULL; i++)
                offer(w);
            break;
        case LUA_TUSERDATA:
            expand_userdata(w, v);
            break;
        case LUA_TTHREAD:
            expand_thread(w, v);
            break;
        }
        lua_settop(L, v - 1);
    }
}

/* A new walk with fresh marks and work list (left on the stack). */
static void begin(walk *w, lua_State *L)
{
    lua_newtable(L);
    w->marks = lua_gettop(L);
    lua_newtable(L);
    w->work = lua_gettop(L);
    w->n = 0;
    w->L = L;
}

/* Lua's roots: the registry (but the host's references unless
 * with_host, and the keys a landscape owns once they are known) and the
 * main stack's values, copied to 2..1 + nstack. */
static void offer_roots(walk *w, const dfle_bridge *b, int nstack, int with_host)
{
    lua_State *L = w->L;
    for (int i = 2; i <= 1 + nstack; i++) {
        lua_pushvalue(L, i);
        offer(w);
    }
    lua_pushnil(L);
    while (lua_next(L, LUA_REGISTRYINDEX)) {
        int skip = 0;
        if (lua_isinteger(L, -2)) {
            lua_Integer k = lua_tointeger(L, -2);
            if (k == b->refs)
                skip = !with_host;
            else if (!w->record_owned && w->owned != 0) {
                skip = lua_rawgeti(L, w->owned, k) != LUA_TNIL;
                lua_pop(L, 1);
            }
        }
        if (skip)
            lua_pop(L, 1);
        else
            offer(w);
        lua_pushvalue(L, -1);
        offer(w);
    }
}

typedef struct owned_req {
    dfle_bridge *b;
    int nstack;
    int nrefs; /* the host's references: no callback has more owners */
    dfle_bridge_owned_fn fn;
    void *ud;
    int count; /* -1: gave up */
} owned_req;

static int owned_p(lua_State *L)
{
    owned_req *q = lua_touserdata(L, 1);
    const dfle_bridge *b = q->b;
    walk w = {0};
    int owned, live, refs;

    /* 1: every landscape, for the registry keys it owns. */
    lua_newtable(L);
    owned = lua_gettop(L);
    begin(&w, L);
    w.owned = owned;
    w.record_owned = 1;
    offer_roots(&w, b, q->nstack, 1);
    run(&w);
    if (w.gave_up)
        return q->count = -1, 0;
    lua_settop(L, owned);
    /* 2: what Lua's own roots keep alive. */
    begin(&w, L);
    live = w.marks;
    w.record_owned = 0;
    offer_roots(&w, b, q->nstack, 0);
    run(&w);
    if (w.gave_up)
        return q->count = -1, 0;
    /* 3: from each host reference, what it alone reaches. */
    lua_newtable(L);
    w.hosts = lua_gettop(L);
    w.live = live;
    lua_rawgeti(L, LUA_REGISTRYINDEX, b->refs);
    refs = lua_gettop(L);
    q->nrefs = 0;
    lua_pushnil(L);
    while (lua_next(L, refs)) {
        int top = lua_gettop(L);
        if (lua_isinteger(L, -2)) {
            q->nrefs++;
            w.owner = lua_tointeger(L, -2);
            begin(&w, L);
            lua_pushvalue(L, top);
            offer(&w);
            run(&w);
            if (w.gave_up)
                return q->count = -1, 0;
        }
        lua_settop(L, top - 1);
    }
    /* Each callback with the references that reach it. */
    {
        int *owners = lua_newuserdatauv(L, (q->nrefs > 0 ? q->nrefs : 1) * sizeof *owners, 0);
        lua_pushnil(L);
        while (lua_next(L, w.hosts)) {
            const host_fn *h = lua_touserdata(L, -2);
            int n = 0;
            lua_pushnil(L);
            while (lua_next(L, -2)) { /* distinct references: at most nrefs */
                if (n < q->nrefs)
                    owners[n++] = (int)lua_tointeger(L, -2);
                lua_pop(L, 1);
            }
            if (h != NULL && h->release != NULL && n > 0) {
                q->fn(q->ud, owners, n, h->ud);
                q->count++;
            }
            lua_pop(L, 1);
        }
    }
    return 0;
}

int dfle_bridge_owned_callbacks(dfle_bridge *b, dfle_bridge_owned_fn fn, void *ud)
{
    lua_State *L = b->main;
    int top = lua_gettop(L);
    owned_req q = {b, top, 0, fn, ud, 0};
    if (b->L != b->main || !lua_checkstack(L, top + 8))
        return -1; /* inside a callback: frames the walk cannot see */
    lua_pushcfunction(L, owned_p);
    lua_pushlightuserdata(L, &q);
    for (int i = 1; i <= top; i++)
        lua_pushvalue(L, i);
    if (lua_pcall(L, 1 + top, 0, 0) != LUA_OK) {
        lua_pop(L, 1);
        return -1;
    }
    return q.count;
}

void dfle_bridge_gc_pause(dfle_bridge *b, int pause)
{
    lua_gc(b->main, pause ? LUA_GCSTOP : LUA_GCRESTART);
}

void dfle_bridge_collect(dfle_bridge *b) { lua_gc(b->main, LUA_GCCOLLECT); }
