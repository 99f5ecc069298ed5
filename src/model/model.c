/*
 * model.c - the model object: its parts, its receiver tree, its state and
 * the fields a user reads (model.h).  The rates are in model_rates.c; how
 * the state moves is the solvers' (src/solvers/).
 *
 * The topology comes from the channel: node i drains to i + 1 over dx.
 * It is stored as a general receiver tree (receivers, flow lengths, a
 * stack in which every node follows its receiver) because everything
 * above the model works on that form, so a drainage network on a grid
 * needs only another topology, not another model or solver.  1 / L is
 * kept as well: slopes are (z_i - z_r) * (1 / L), the form the model
 * has always used, so results do not move in the last bit.
 */
#include "dfle/model.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/file.h"
#include "dfle/flow.h"
#include "dfle/param.h"
#include "dfle/record.h"
#include "model/model_internal.h"

void dfle_model_opts_default(dfle_model_opts *o)
{
    memset(o, 0, sizeof *o);
    o->U = 5e-4;
    o->cfl = 0.5;
    o->dt_max = 1000.0;
    o->df_combine = DFLE_DF_ANY;
}

static const struct {
    const char *name, *unit;
} field_info[DFLE_FIELD_COUNT] = {
    [DFLE_FIELD_X] = {"x", "m"},           [DFLE_FIELD_A] = {"A", "m^2"},
    [DFLE_FIELD_W] = {"w", "m"},           [DFLE_FIELD_Z] = {"z", "m"},
    [DFLE_FIELD_S] = {"S", "-"},           [DFLE_FIELD_E_F] = {"E_f", "m/yr"},
    [DFLE_FIELD_E_DF] = {"E_df", "m/yr"},  [DFLE_FIELD_DZDT] = {"dzdt", "m/yr"},
    [DFLE_FIELD_M] = {"M", "m^3"},         [DFLE_FIELD_Q] = {"Q", "m^3/s"},
    [DFLE_FIELD_H] = {"h", "m"},           [DFLE_FIELD_V] = {"v", "m/s"},
    [DFLE_FIELD_T_P] = {"t_p", "s"},       [DFLE_FIELD_TAU] = {"tau", "Pa"},
    [DFLE_FIELD_THETA] = {"Theta", "-"},
};

int dfle_field_lookup(const char *name)
{
    for (int f = 0; f < DFLE_FIELD_COUNT; f++)
        if (strcmp(name, field_info[f].name) == 0)
            return f;
    return -1;
}

const char *dfle_field_name(int f)
{
    return f >= 0 && f < DFLE_FIELD_COUNT ? field_info[f].name : NULL;
}

const char *dfle_field_unit(int f)
{
    return f >= 0 && f < DFLE_FIELD_COUNT ? field_info[f].unit : NULL;
}

/* The fields every model uses; the celerity's perturbed copies come
 * with its first call (dfle_model_pert_alloc): the implicit and direct
 * solvers and a landscape's implicit steps never ask for them. */
enum { MODEL_ARRAYS = 9, PERT_ARRAYS = 4 };

static int model_alloc(dfle_model *m, dfle_error *err)
{
    size_t n = m->n;
    double *block = calloc(MODEL_ARRAYS * n, sizeof *block);

    if (block == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "model: out of memory for %zu nodes", n);
    m->z = block;
    m->S = block + n;
    m->E_f = block + 2 * n;
    m->E_df = block + 3 * n;
    m->dzdt = block + 4 * n;
    m->F = block + 5 * n;
    m->S_routed = block + 6 * n;
    m->inv_len = block + 7 * n;
    m->KAm = block + 8 * n;
    m->reached.node = malloc(n * sizeof *m->reached.node);
    if (m->reached.node == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "model: out of memory for %zu nodes", n);
    dfle_flow_bind(&m->node, m->node_block, 1);
    return dfle_flow_init(&m->flow, n, err);
}

int dfle_model_pert_alloc(dfle_model *m, dfle_error *err)
{
    const size_t n = m->n;
    double *block;
    if (m->S_pert != NULL)
        return DFLE_OK;
    block = calloc(PERT_ARRAYS * n, sizeof *block);
    m->reached_pert.node = malloc(n * sizeof *m->reached_pert.node);
    if (block == NULL || m->reached_pert.node == NULL ||
        dfle_flow_init(&m->flow_pert, n, NULL) != DFLE_OK) {
        free(block);
        free(m->reached_pert.node);
        m->reached_pert.node = NULL;
        return dfle_error_set(err, DFLE_ENOMEM, "model: out of memory for the celerity of %zu "
                              "nodes", n);
    }
    m->S_pert = block;
    m->E_pert = block + n;
    m->F_pert = block + 2 * n;
    m->celerity = block + 3 * n;
    return DFLE_OK;
}

size_t dfle_model_memory(const dfle_model *m)
{
    const size_t n = m->n;
    size_t b = sizeof *m + n * (MODEL_ARRAYS * sizeof(double) + sizeof(size_t)) +
               DFLE_FLOW_ARRAYS * n * sizeof(double);
    if (m->S_pert != NULL)
        b += n * (PERT_ARRAYS * sizeof(double) + sizeof(size_t)) +
             DFLE_FLOW_ARRAYS * n * sizeof(double);
    if (m->g_block != NULL)
        b += (5 + DFLE_FLOW_ARRAYS) * n * sizeof(double);
    return b + dfle_model_pop_memory(m);
}

void dfle_model_sync_domain(dfle_model *m)
{
    const unsigned long long v = dfle_network_version(m->net);
    const double *L, *A;
    if (v == m->net_version)
        return; /* the common case: every node solve asks */
    L = dfle_network_length(m->net), A = dfle_network_A(m->net);
    for (size_t i = 0; i < m->n; i++)
        m->inv_len[i] = 1.0 / L[i];
    m->channel = dfle_network_channel(m->net);
    if (m->fl != NULL) {
        /* K A^m is fixed per shape: hoist its pow() out of the step loop;
         * hillslopes (off the channel mask) have no fluvial erosion. */
        for (size_t i = 0; i < m->n; i++)
            m->KAm[i] = m->channel == NULL || m->channel[i]
                            ? dfle_fluvial_K(m->fl) * pow(A[i], dfle_fluvial_m(m->fl))
                            : 0.0;
        if (m->K_scale != NULL)
            for (size_t i = 0; i < m->n; i++)
                m->KAm[i] *= m->K_scale[i];
    }
    m->net_version = v;
    dfle_model_invalidate_flow(m); /* areas moved: the flow must be routed again */
}

#ifndef NDEBUG
/* The invariants everything above the model relies on: receivers are
 * nodes, base nodes are their own receivers, every other node comes
 * after its receiver in the stack and has a positive flow length. */
static int topology_ok(const dfle_model *m)
{
    const size_t *stack = dfle_model_stack(m), *recv = dfle_model_receivers(m);
    const double *len = dfle_model_flow_length(m);
    size_t *pos = malloc(m->n * sizeof *pos);
    int ok = 1;
    if (pos == NULL)
        return 1; /* cannot check: not a broken invariant */
    for (size_t k = 0; k < m->n; k++)
        pos[stack[k]] = k;
    for (size_t i = 0; ok && i < m->n; i++) {
        size_t r = recv[i];
        ok = r < m->n && (r == i || (pos[r] < pos[i] && len[i] > 0));
    }
    free(pos);
    return ok;
}
#endif

void dfle_model_free(dfle_model *m)
{
    if (m == NULL)
        return;
    dfle_flow_release(&m->flow);
    dfle_flow_release(&m->flow_pert);
    dfle_model_pop_free(m);
    free(m->z); /* the field block starts at z */
    free(m->reached.node);
    free(m->S_pert); /* the perturbed block starts at S_pert */
    free(m->reached_pert.node);
    free(m->g_block);
    dfle_network_free(m->own_net);
    free(m);
}

int dfle_model_new(const dfle_model_opts *o, dfle_model **out, dfle_error *err)
{
    dfle_model *m;
    int st;

    *out = NULL;
    if ((o->channel == NULL) == (o->network == NULL))
        return dfle_error_set(err, DFLE_EINVAL,
                              "model: channel is required (or a network: give exactly one)");
    if (o->router != NULL && o->law == NULL)
        return dfle_error_set(err, DFLE_EINVAL,
                              "model: a debris-flow router needs an erosion law (law)");
    if (!(isfinite(o->U) && o->U > 0))
        return dfle_error_set(err, DFLE_EINVAL, "model: U must be > 0 m/yr (got %g)", o->U);
    if (!(isfinite(o->cfl) && o->cfl > 0 && o->cfl <= 1))
        return dfle_error_set(err, DFLE_EINVAL, "model: cfl must be in (0, 1] (got %g)", o->cfl);
    if (!(isfinite(o->dt_max) && o->dt_max > 0))
        return dfle_error_set(err, DFLE_EINVAL, "model: dt_max must be > 0 yr (got %g)",
                              o->dt_max);
    if (o->df_combine < DFLE_DF_ANY || o->df_combine > DFLE_DF_CUSTOM ||
        (o->df_combine == DFLE_DF_CUSTOM && o->df_frequency == NULL))
        return dfle_error_set(err, DFLE_EINVAL, "model: df_combine must be ANY, COUNT or CUSTOM "
                              "with a frequency function (got %d)", o->df_combine);

    m = calloc(1, sizeof *m);
    if (m == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "model: out of memory");
    m->ch = o->channel;
    m->fl = o->fluvial;
    m->rt = o->router;
    m->law = o->router != NULL ? o->law : NULL;
    m->U = o->U;
    m->cfl = o->cfl;
    m->dt_max = o->dt_max;
    m->combine = o->df_combine;
    m->frequency = o->df_frequency;
    m->frequency_ud = o->df_frequency_ud;
    st = DFLE_OK;
    if (o->channel != NULL)
        st = dfle_network_new_chain(o->channel, &m->own_net, err);
    if (st == DFLE_OK) {
        m->net = o->channel != NULL ? m->own_net : o->network;
        m->n = dfle_network_size(m->net);
        assert(m->n >= 2);
        st = model_alloc(m, err);
    }
    if (st == DFLE_OK)
        st = dfle_model_pop_new(m, err);
    if (st == DFLE_OK) {
        dfle_model_sync_domain(m);
        assert(topology_ok(m));
        st = dfle_model_init_fluvial_steady(m, NULL, err);
    }
    if (st != DFLE_OK) {
        dfle_model_free(m);
        return st;
    }
    *out = m;
    return DFLE_OK;
}

size_t dfle_model_size(const dfle_model *m) { return m->n; }
double dfle_model_time(const dfle_model *m) { return m->time; }
double dfle_model_U(const dfle_model *m) { return m->U; }
double dfle_model_cfl(const dfle_model *m) { return m->cfl; }
double dfle_model_dt_max(const dfle_model *m) { return m->dt_max; }

size_t dfle_model_params(const dfle_model *m, dfle_param *out, size_t cap)
{
    const dfle_param p[] = {
        {"U", m->U, "m/yr", 0},
        {"cfl", m->cfl, "", 0},
        {"dt_max", m->dt_max, "yr", 0},
    };
    return dfle_param_copy(p, sizeof p / sizeof p[0], out, cap);
}
const dfle_channel *dfle_model_channel(const dfle_model *m) { return m->ch; }
const dfle_fluvial *dfle_model_fluvial(const dfle_model *m) { return m->fl; }
dfle_router *dfle_model_router(const dfle_model *m) { return m->rt; }
dfle_law *dfle_model_law(const dfle_model *m) { return m->law; }
const dfle_network *dfle_model_network(const dfle_model *m) { return m->net; }
const size_t *dfle_model_receivers(const dfle_model *m) { return dfle_network_receivers(m->net); }
const double *dfle_model_flow_length(const dfle_model *m) { return dfle_network_length(m->net); }
const size_t *dfle_model_stack(const dfle_model *m) { return dfle_network_stack(m->net); }
double *dfle_model_z(dfle_model *m) { return m->z; }

int dfle_model_is_base(const dfle_model *m, size_t i)
{
    return dfle_network_is_base(m->net, i);
}

int dfle_model_uniform_flow_length(const dfle_model *m)
{
    return dfle_network_uniform_length(m->net);
}

void dfle_model_advance_time(dfle_model *m, double dt)
{
    assert(dt >= 0);
    m->time += dt;
}

int dfle_model_set_U(dfle_model *m, double U, dfle_error *err)
{
    if (!(isfinite(U) && U > 0))
        return dfle_error_set(err, DFLE_EINVAL, "model: U must be > 0 m/yr (got %g)", U);
    if (U != m->U) {
        m->U = U;
        m->evaluated = 0; /* dz/dt = U - E changes; E does not */
    }
    return DFLE_OK;
}

void dfle_model_touch(dfle_model *m)
{
    m->evaluated = 0;
}

void dfle_model_invalidate_flow(dfle_model *m)
{
    m->evaluated = 0;
    m->flow_valid = 0;
}

int dfle_model_init_fluvial_steady(dfle_model *m, const dfle_fluvial *fl,
                                   dfle_error *err)
{
    dfle_fluvial *own = NULL;
    const double *A = dfle_network_A(m->net), *L = dfle_network_length(m->net);
    const size_t *stack = dfle_network_stack(m->net), *recv = dfle_network_receivers(m->net);
    int st;

    if (fl == NULL)
        fl = m->fl;
    if (fl == NULL || !(dfle_fluvial_K(fl) > 0)) {
        /* The paper's runs all start from Eq. (26) with the Table G1 law,
         * including those that switch fluvial erosion off. */
        dfle_stochastic_threshold_opts o;
        dfle_stochastic_threshold_opts_default(&o);
        st = dfle_fluvial_new_stochastic_threshold(&o, &own, err);
        if (st != DFLE_OK)
            return st;
        fl = own;
    }
    /* Up from base level (z = 0), each node after its receiver. */
    st = DFLE_OK;
    for (size_t k = 0; k < m->n; k++) {
        const size_t i = stack[k];
        const int base = recv[i] == i;
        const double S = base ? 0.0 : dfle_fluvial_steady_slope(fl, m->U, A[i]);
        m->z[i] = base ? 0.0 : m->z[recv[i]] + L[i] * S;
        if (!isfinite(m->z[i])) {
            /* (U/K)^(1/n_s) overflows for a tiny n_s: no profile to start from. */
            st = dfle_error_set(
                err, DFLE_ENUMERIC,
                "model: the starting profile, the fluvial steady state S = (U/K)^(1/n_s) "
                "A^(-m_s/n_s) of Eq. (26), is not finite at node %zu (A = %g m^2: S = %g, z = %g m) "
                "for K = %g, m_s = %g, n_s = %g, U = %g m/yr; use a fluvial law with a finite "
                "steady slope",
                i + 1, A[i], S, m->z[i], dfle_fluvial_K(fl), dfle_fluvial_m(fl), dfle_fluvial_n(fl),
                m->U);
            break;
        }
    }
    dfle_fluvial_free(own);
    dfle_model_invalidate_flow(m);
    return st;
}

int dfle_model_set_erodibility(dfle_model *m, const double *K_scale, const double *df_scale,
                               dfle_error *err)
{
    for (size_t i = 0; i < m->n; i++)
        if ((K_scale != NULL && !(isfinite(K_scale[i]) && K_scale[i] >= 0)) ||
            (df_scale != NULL && !(isfinite(df_scale[i]) && df_scale[i] >= 0)))
            return dfle_error_set(err, DFLE_EINVAL, "model: erodibility scale at node %zu is "
                                  "%g (K) and %g (E_df); both must be finite and >= 0", i + 1,
                                  K_scale != NULL ? K_scale[i] : 1.0,
                                  df_scale != NULL ? df_scale[i] : 1.0);
    m->K_scale = K_scale;
    m->df_scale = df_scale;
    m->net_version = 0; /* renew K A^m at the next evaluation */
    dfle_model_invalidate_flow(m);
    return DFLE_OK;
}

int dfle_model_set_z(dfle_model *m, const double *z, size_t n, dfle_error *err)
{
    if (n != m->n)
        return dfle_error_set(err, DFLE_EINVAL, "model: z has %zu values, the channel %zu nodes",
                              n, m->n);
    for (size_t i = 0; i < n; i++)
        if (!isfinite(z[i]))
            return dfle_error_set(err, DFLE_EINVAL, "model: z at node %zu is not finite (%g)",
                                  i + 1, z[i]);
    memcpy(m->z, z, n * sizeof *z);
    dfle_model_invalidate_flow(m);
    return DFLE_OK;
}

const double *dfle_model_field(dfle_model *m, int field, dfle_error *err)
{
    if (!m->evaluated && dfle_model_evaluate(m, err) != DFLE_OK)
        return NULL;
    switch (field) {
    case DFLE_FIELD_X: return dfle_network_x(m->net);
    case DFLE_FIELD_A: return dfle_network_A(m->net);
    case DFLE_FIELD_W: return dfle_network_w(m->net);
    case DFLE_FIELD_Z: return m->z;
    case DFLE_FIELD_S: return m->S;
    case DFLE_FIELD_E_F: return m->E_f;
    case DFLE_FIELD_E_DF: return m->E_df;
    case DFLE_FIELD_DZDT: return m->dzdt;
    case DFLE_FIELD_M: return m->flow.M;
    case DFLE_FIELD_Q: return m->flow.Q;
    case DFLE_FIELD_H: return m->flow.h;
    case DFLE_FIELD_V: return m->flow.v;
    case DFLE_FIELD_T_P: return m->flow.t_p;
    case DFLE_FIELD_TAU: return m->flow.tau;
    case DFLE_FIELD_THETA: return m->flow.Theta;
    default:
        dfle_error_set(err, DFLE_EINVAL, "model: no field number %d", field);
        return NULL;
    }
}

int dfle_model_write_csv(dfle_model *m, const char *path, const dfle_record *rec,
                         dfle_error *err)
{
    dfle_column cols[DFLE_FIELD_COUNT];

    for (int k = 0; k < DFLE_FIELD_COUNT; k++) {
        cols[k].name = field_info[k].name;
        cols[k].unit = field_info[k].unit;
        cols[k].text = NULL;
        if ((cols[k].num = dfle_model_field(m, k, err)) == NULL)
            return err != NULL ? err->code : DFLE_ESTATE;
    }
    /* 10 significant digits: far beyond what the model resolves, and
     * short enough to read. */
    return dfle_table_write(path, "model", rec, cols, DFLE_FIELD_COUNT, m->n, 10, err);
}

/* One component: its kind, and its params op's list when it has one. */
static void describe_component(dfle_record *rec, const char *section, const char *kind,
                               size_t (*params)(const void *, dfle_param *, size_t),
                               const void *comp)
{
    dfle_param p[64];
    size_t n;
    dfle_record_section(rec, section, comp != NULL ? kind : "off");
    if (comp == NULL || (n = params(comp, p, 64)) == (size_t)-1)
        return;
    dfle_record_params(rec, p, n < 64 ? n : 64);
}

static size_t channel_params(const void *c, dfle_param *p, size_t cap)
{
    return dfle_channel_params(c, p, cap);
}
static size_t fluvial_params(const void *c, dfle_param *p, size_t cap)
{
    return dfle_fluvial_params(c, p, cap);
}
static size_t router_params(const void *c, dfle_param *p, size_t cap)
{
    return dfle_router_params(c, p, cap);
}
static size_t law_params(const void *c, dfle_param *p, size_t cap)
{
    return dfle_law_params(c, p, cap);
}
static size_t model_params(const void *c, dfle_param *p, size_t cap)
{
    return dfle_model_params(c, p, cap);
}

void dfle_model_describe(const dfle_model *m, dfle_record *rec)
{
    const double *x = dfle_network_x(m->net), *A = dfle_network_A(m->net);
    if (m->ch != NULL) {
        describe_component(rec, "channel", dfle_channel_kind(m->ch), channel_params,
                           m->ch);
        dfle_record_number(rec, "n", (double)m->n, NULL);
        dfle_record_number(rec, "x_outlet", x[m->n - 1], "m");
        dfle_record_number(rec, "A_head", A[0], "m^2");
        dfle_record_number(rec, "A_outlet", A[m->n - 1], "m^2");
    } else {
        dfle_record_section(rec, "network", NULL);
        dfle_record_number(rec, "n", (double)m->n, NULL);
    }
    describe_component(rec, "fluvial", m->fl ? dfle_fluvial_name(m->fl) : NULL,
                       fluvial_params, m->fl);
    describe_component(rec, "router", m->rt ? dfle_router_name(m->rt) : NULL,
                       router_params, m->rt);
    describe_component(rec, "law", m->law ? dfle_law_name(m->law) : NULL, law_params, m->law);
    describe_component(rec, "model", NULL, model_params, m);
    dfle_record_number(rec, "time", m->time, "yr");
}
