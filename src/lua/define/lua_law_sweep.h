/*
 * lua_law_sweep.h - the state of a dfle.law.define law and the bottom
 * of its three layers: the Lua sweep (lua_law_sweep.c), which runs the
 * user's functions node by node.  Above it, lua_law_compiled.c runs them
 * as compiled programs and checks those against the sweep; on top,
 * lua_law_define.c builds the law and its ops dispatch between the two.
 * Internal to the binding.
 */
#ifndef DFLE_LUA_LAW_SWEEP_H
#define DFLE_LUA_LAW_SWEEP_H

#include "lua/core/lua_shell.h"
#include "lua/trace/lua_trace.h"

/* Fixed slots on the law thread's stack (lua_shell.h: the shell's own
 * come first). */
enum {
    SLOT_PARAMS = DFLE_SHELL_PARAMS, /* p: the law's own copy of params */
    SLOT_MSGH = DFLE_SHELL_MSGH,     /* message handler (traceback)      */
    SLOT_STATE = DFLE_SHELL_STATE,   /* the lua_law (a userdata: collected with the law) */
    SLOT_RATE,      /* rate(c, p)                         */
    SLOT_FACTOR,    /* factor(c, p) or nil                */
    SLOT_INTEGRAND, /* integrand(h, v, lambda, p) or nil  */
    SLOT_FREQUENCY, /* frequency(A, p) or nil             */
    /* Lua arrays the drivers read (and `out`, which they write). */
    ARR_S, ARR_A, ARR_W, ARR_H, ARR_V, ARR_T_P, ARR_TAU, ARR_THETA, ARR_Q, ARR_M, ARR_I, ARR_F,
    ARR_OUT,
    SLOT_REC_FACTOR, /* c for factor (fields on demand, see fetch()) */
    SLOT_REC_RATE,  /* c for rate                         */
    SLOT_REC_RATE_TR, /* c for rate after a time-resolved routing */
    SLOT_POS,       /* {i}: the node the drivers are at   */
    SLOT_DRV_FACTOR, /* Lua loop calling factor per node  */
    SLOT_DRV_RATE,  /* Lua loop calling rate per node     */
    SLOT_DRV_RATE_TR, /* the same, time-resolved flows    */
    SLOT_SWEEP,     /* the sweep closure over the slots above */
    /* Guard tables of the compiled functions (lua_trace.h), per op, and
     * of the integrand; nil while not compiled. */
    SLOT_GUARDS_FACTOR, SLOT_GUARDS_RATE, SLOT_GUARDS_RATE_TR, SLOT_GUARDS_G,
    SLOT_COUNT = SLOT_GUARDS_G
};
#define N_IN (ARR_F - ARR_S + 1) /* input arrays, each with a C shadow */

/* Field names, in the order of the ARR_ slots (valid Lua names: the
 * generated drivers use them as local variables). */
extern const char *const ll_field_names[N_IN];
enum { F_S, F_A, F_W, F_H, F_V, F_T_P, F_TAU, F_THETA, F_Q, F_M, F_I, F_F };
/* Fields rate() sees when the law has a factor: the slope part only. */
#define SPLIT_RATE_FIELDS ((1u << F_S) | (1u << F_A) | (1u << F_W) | (1u << F_F))

/* The three kinds of sweep, each with its own record, driver and set of
 * fields read.  Rate after a time-resolved routing sees the slope part
 * only (S, A, w, F): the model's node solver then calls rate on a cached
 * factor without a valid flow view (model_node.c), so the flow must not
 * be read; the law knows which case it is in from its last flow_factor. */
enum { OP_FACTOR, OP_RATE, OP_RATE_TR, N_OPS };
enum { G_NONE, G_POWER, G_LUA };

typedef struct lua_law {
    dfle_lua_shell sh; /* the thread (user value 1 of the law object), name, who */
    /* A copy of the law's ops named after the user's law, so
     * dfle_law_name() and error messages say "inertial", not "lua". */
    dfle_law_ops ops;
    int has_factor, has_frequency;
    int g_kind;             /* G_NONE, G_POWER (h^gh v^gv lambda^gl), G_LUA */
    double gh, gv, gl;
    /* C shadows of the input arrays: what each Lua array holds now. */
    size_t cap;
    double *shadow; /* N_IN blocks of cap values */
    /* frequency(A) memo, sorted by A. */
    size_t nf, capf;
    double *fA, *fv;
    /* Fields each op's function has read (bit F_x), and whether its
     * driver must be generated again to copy a newly read one. */
    unsigned used[N_OPS];
    int dirty[N_OPS];
    int time_resolved; /* the last flow_factor saw a time-resolved flow */
    /* Rate evaluated ahead for a one-node flow_factor (see sweep()). */
    int spec_valid;
    double spec_S, spec_F, spec_A, spec_w, spec_E;
    /* Compiled forms (lua_trace.h) of factor and rate per op, and of the
     * integrand: cstate 0 = not tried yet, 1 = compiled, -1 = runs as Lua
     * (why[] says why).  seen[] is the epoch at which the program's
     * guards last held.  cache: programs come from and go to the
     * state's cache (lua_trace_cache.c), with float params as inputs. */
    int compile, cache;
    unsigned long *epoch;
    dfle_trace_prog *prog[N_OPS];
    int cstate[N_OPS];
    int unchecked[N_OPS]; /* traced, not yet checked against Lua */
    unsigned long seen[N_OPS];
    char why[N_OPS][160];
    dfle_trace_prog *gprog;
    int gstate, gverify;
    unsigned long gseen;
    char gwhy[160];
    double *scratch; /* a compiled sweep checked against Lua */
    size_t scratch_cap;
    double *dbuf; /* derivative columns of the inputs (ll_compiled_rate_dlnS) */
    size_t dcap;
    /* What each program's values (held in it until its next evaluation)
     * were computed for: the slope and factor arrays (rate) or the flow
     * (factor), n and the values' address; fresh = 0: nothing known.
     * rate_dlnS differentiates those values when they are the call's. */
    int fresh[N_OPS];
    const void *fresh_in[N_OPS][2];
    size_t fresh_n[N_OPS];
    const double *fresh_val[N_OPS];
    /* The op in progress, read by the sweep. */
    int busy, op;
    const dfle_law_ctx *ctx;
    const double *F_in;
    double *out;
} lua_law;

/* Push the slots the sweep needs, from the arrays to the drivers, then
 * the sweep closure (SLOT_SWEEP): the thread holds SLOT_FREQUENCY slots
 * and ll is the state at SLOT_STATE. */
void ll_sweep_slots(lua_State *T, lua_law *ll);

/* The C array behind field f for the op in progress (NULL: zeros). */
const double *ll_field_source(const lua_law *ll, int f);
/* Where drainage area A is, or would go, in the frequency(A) memo; 1 if
 * it is there. */
int ll_memo_find(const lua_law *ll, double A, size_t *at);
/* Run one op as a protected sweep of the user's Lua function. */
int ll_interpreted_sweep(lua_law *ll, int op, const dfle_law_ctx *ctx, const double *F_in,
                         double *out, dfle_error *err);
/* The integrand through the user's Lua function (one protected call);
 * fails like an op. */
int ll_lua_integrand(lua_law *ll, double h, double v, double lambda, double *g,
                     dfle_error *err);

#endif
