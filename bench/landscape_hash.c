/*
 * landscape_hash.c - fingerprints of landscape steps: the elevations,
 * receivers and drainage areas after a few implicit steps, each hashed
 * (FNV-1a, 64 bits, over their bytes), for square grids of 30 m cells
 * from seeded noise with every edge a base level:
 *
 *   sp   stream power, m = 0.5, n = 1 (K = 2e-5) or 2.33 (K = 1e-3),
 *        every cell a channel (A_0 = 0), steps of 1e3 yr;
 *   df   the same with debris flows (empirical router, power law, both
 *        with the defaults of Fig. 9) on channels above A_0 = 1e4 m^2,
 *        the noise on a pyramid of slope 0.05 (so that flows travel);
 *   fig9 the Fig. 9 components (stochastic-threshold fluvial law,
 *        m_s = 1.4, n_s = 2.33) on that start.
 * Each line ends with the cells the last step's flows reached.
 *
 * A change that claims to leave the numbers as they were is checked by
 * running this before and after it and comparing the lines (or with
 * --check FILE, which reads lines written before and says which
 * differ).  The threads a landscape uses (DFLE_LANDSCAPE_THREADS when
 * set) must not change a hash.
 *
 *   build/bench/landscape_hash [--check FILE] [side ...]   (250 500 1000 2000)
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/landscape.h"
#include "dfle/law_power.h"
#include "dfle/router_empirical.h"

#include "bench.h"

static uint64_t fnv1a(const void *p, size_t bytes)
{
    const unsigned char *b = p;
    uint64_t h = 0xcbf29ce484222325ull;
    for (size_t i = 0; i < bytes; i++) {
        h ^= b[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

typedef struct config {
    const char *name;
    double n_exp;
    int debris, fig9;
} config;

static const config configs[] = {
    {"sp", 1.0, 0, 0}, {"sp", 2.33, 0, 0}, {"df", 1.0, 1, 0}, {"df", 2.33, 1, 0},
    {"fig9", 2.33, 1, 1},
};

/* One line: name, side, n, the three hashes; 0 or 1 on failure. */
static int run(const config *cf, size_t side, int steps, char *line, size_t cap, double *cpu)
{
    const size_t n = side * side;
    uint64_t x = BENCH_NOISE_SEED;
    double *z = malloc(n * sizeof *z);
    dfle_fluvial *fl = NULL;
    dfle_router *rt = NULL;
    dfle_law *law = NULL;
    dfle_landscape *ls = NULL;
    dfle_landscape_opts o;
    dfle_landscape_status st;
    dfle_error err;
    int rc = 1;

    if (z == NULL)
        return 1;
    bench_noise(z, n, &x);
    if (cf->debris) /* a pyramid of slope 0.05 under the noise: flows that travel */
        for (size_t i = 0; i < n; i++) {
            size_t r = i / side, c = i % side, e = r < c ? r : c;
            e = e < side - 1 - r ? e : side - 1 - r;
            e = e < side - 1 - c ? e : side - 1 - c;
            z[i] += 0.05 * 30.0 * (double)e;
        }
    dfle_landscape_opts_default(&o);
    o.nx = o.ny = side;
    o.dx = o.dy = 30.0;
    o.z = z;
    o.A0 = cf->debris ? 1e4 : 0.0;
    o.U.value = 1e-3;
    if (cf->fig9) {
        dfle_stochastic_threshold_opts so;
        dfle_stochastic_threshold_opts_default(&so);
        if (dfle_fluvial_new_stochastic_threshold(&so, &fl, &err) != DFLE_OK)
            goto fail;
    } else if (dfle_fluvial_new_stream_power(cf->n_exp == 1 ? 2e-5 : 1e-3, 0.5, cf->n_exp, &fl,
                                             &err) != DFLE_OK) {
        goto fail;
    }
    o.fluvial = fl;
    if (cf->debris) {
        dfle_empirical_opts eo;
        dfle_power_law_opts po;
        dfle_empirical_opts_default(&eo);
        dfle_power_law_opts_default(&po);
        if (dfle_router_new_empirical(&eo, &rt, &err) != DFLE_OK ||
            dfle_law_new_power(&po, &law, &err) != DFLE_OK)
            goto fail;
        o.router = rt;
        o.law = law;
    }
    if (dfle_landscape_new(&o, &ls, &err) != DFLE_OK)
        goto fail;
    {
        double t0 = cpu_seconds();
        for (int s = 0; s < steps; s++)
            if (dfle_landscape_step(ls, 1e3, 1e-3, &st, &err) != DFLE_OK)
                goto fail;
        *cpu = cpu_seconds() - t0;
    }
    {
        const dfle_drainage *dr = dfle_landscape_drainage(ls);
        snprintf(line, cap, "%-4s %5zu n=%.2f z=%016llx rcv=%016llx A=%016llx reached=%zu",
                 cf->name, side, cf->n_exp, (unsigned long long)fnv1a(dfle_landscape_z(ls), n * sizeof(double)),
                 (unsigned long long)fnv1a(dfle_drainage_receivers(dr), n * sizeof(uint32_t)),
                 (unsigned long long)fnv1a(dfle_drainage_area(dr), n * sizeof(double)), st.reached);
    }
    rc = 0;
    goto done;
fail:
    fprintf(stderr, "landscape hash: %s\n", err.msg);
done:
    dfle_landscape_free(ls);
    dfle_law_free(law);
    dfle_router_free(rt);
    dfle_fluvial_free(fl);
    free(z);
    return rc;
}

/* The line of `ref` that starts as `line` does (name, side, n), or NULL. */
static const char *find_line(char **ref, int n_ref, const char *line)
{
    for (int k = 0; k < n_ref; k++)
        if (strncmp(ref[k], line, 17) == 0)
            return ref[k];
    return NULL;
}

int main(int argc, char **argv)
{
    static const size_t default_sides[] = {250, 500, 1000, 2000};
    size_t sides[16];
    int n_sides = 0, n_ref = 0, differ = 0, compared = 0;
    char *ref[256];
    const char *check = NULL;

    for (int a = 1; a < argc; a++) {
        if (strcmp(argv[a], "--check") == 0 && a + 1 < argc)
            check = argv[++a];
        else if (n_sides < 16)
            sides[n_sides++] = (size_t)strtoul(argv[a], NULL, 10);
    }
    if (n_sides == 0)
        for (size_t s = 0; s < sizeof default_sides / sizeof *default_sides; s++)
            sides[n_sides++] = default_sides[s];
    if (check != NULL) {
        FILE *f = fopen(check, "r");
        char buf[256];
        if (f == NULL) {
            fprintf(stderr, "landscape hash: cannot read %s\n", check);
            return 1;
        }
        while (n_ref < 256 && fgets(buf, sizeof buf, f) != NULL) {
            buf[strcspn(buf, "\n")] = '\0';
            ref[n_ref++] = strdup(buf);
        }
        fclose(f);
    }
    for (int k = 0; k < n_sides; k++)
        for (size_t c = 0; c < sizeof configs / sizeof *configs; c++) {
            char line[256];
            double cpu = 0;
            const char *r;
            if (run(&configs[c], sides[k], 3, line, sizeof line, &cpu) != 0)
                return 1;
            if (check == NULL) {
                printf("%s\n", line);
            } else {
                r = find_line(ref, n_ref, line);
                compared += r != NULL;
                differ += r != NULL && strcmp(r, line) != 0;
                printf("%s %s (%.2f s)\n", line,
                       r == NULL ? "new" : strcmp(r, line) == 0 ? "identical" : "DIFFERS", cpu);
            }
            fflush(stdout);
        }
    if (check != NULL)
        printf("%d of %d lines identical\n", compared - differ, compared);
    for (int k = 0; k < n_ref; k++)
        free(ref[k]);
    return differ != 0;
}
