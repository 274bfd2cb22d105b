/*
 * The C test of the pfe C API (run by tests/c_api.rs, which compiles it with the host's cc
 * against libpfe_capi.a).
 *
 *   pfe_test errors         every error path: NULL, short and misaligned memory, an
 *                           extractor not set up, NaN arguments, bad configurations, indices
 *                           and buffers; prints "errors: N checks passed" or fails (exit 1)
 *   pfe_test extract FILE   extracts every scan of FILE with the paper's and the default
 *                           configuration, from mm and from raw codes, and prints each result
 *                           with every float as its bits (compared with pfe-core's output)
 *
 * FILE, written by tests/c_api.rs, per scan (floats as the hex of their IEEE-754 bits):
 *   S id sigma_r sigma_sys sweeps quantum unit start step r_max has_motion v omega beam_dt
 *     sweep_dt timing_sweeps n
 *   R n range bits (mm)
 *   C n raw codes
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pfe.h"

/* The extractor: static memory, no allocation. */
static pfe_extractor ex;

static uint32_t bits(float f) {
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static float from_bits(uint32_t u) {
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static int failures = 0;
static int checks = 0;

#define EXPECT(cond)                                                                   \
    do {                                                                               \
        checks++;                                                                      \
        if (!(cond)) {                                                                 \
            failures++;                                                                \
            fprintf(stderr, "%s:%d: expected %s\n", __FILE__, __LINE__, #cond);        \
        }                                                                              \
    } while (0)

static int errors(void) {
    static pfe_extractor other; /* never set up (zero, as a static is) */
    static _Alignas(8) uint8_t raw[PFE_EXTRACTOR_SIZE + 8];
    pfe_config cfg;
    pfe_geometry g;
    pfe_scan_options opt;
    pfe_feature f;
    pfe_stats st;
    uint16_t marks[4];
    size_t count = 99;
    float ranges[361];
    uint16_t codes[361];
    for (int i = 0; i < 361; i++) {
        ranges[i] = 1500.0f; /* a round room: one circle */
        codes[i] = 1500;
    }

    EXPECT(pfe_extractor_size() <= PFE_EXTRACTOR_SIZE);
    EXPECT(pfe_extractor_align() <= PFE_EXTRACTOR_ALIGN);
    EXPECT(sizeof(pfe_extractor) == PFE_EXTRACTOR_SIZE);
    EXPECT(_Alignof(pfe_extractor) == PFE_EXTRACTOR_ALIGN);

    /* Set-up: NULL, short, misaligned; raw aligned bytes work as well as the type. */
    EXPECT(pfe_extractor_init(NULL, sizeof ex) == PFE_ERR_NULL);
    EXPECT(pfe_extractor_init(&ex, pfe_extractor_size() - 1) == PFE_ERR_BUFFER_TOO_SMALL);
    EXPECT(pfe_extractor_init((pfe_extractor *)(raw + 4), PFE_EXTRACTOR_SIZE) ==
           PFE_ERR_MISALIGNED);
    EXPECT(pfe_extractor_init((pfe_extractor *)raw, PFE_EXTRACTOR_SIZE) == PFE_OK);
    EXPECT(pfe_extractor_init(&ex, sizeof ex) == PFE_OK);

    EXPECT(pfe_config_default(NULL) == PFE_ERR_NULL);
    EXPECT(pfe_config_default(&cfg) == PFE_OK);
    EXPECT(pfe_config_check(&cfg) == PFE_OK);
    EXPECT(pfe_config_check(NULL) == PFE_ERR_NULL);
    EXPECT(pfe_geometry_lms200(180.0f, 0.5f, NULL) == PFE_ERR_NULL);
    EXPECT(pfe_geometry_lms200(180.0f, NAN, &g) == PFE_ERR_INVALID_GEOMETRY);
    EXPECT(pfe_geometry_lms200(180.0f, 0.0f, &g) == PFE_ERR_INVALID_GEOMETRY);
    EXPECT(pfe_geometry_lms200(180.0f, 0.5f, &g) == PFE_OK);
    EXPECT(pfe_scan_options_default(&opt) == PFE_OK);
    EXPECT(opt.sweeps == 1 && opt.has_motion == 0 && opt.quantum == 0.0f);

    /* Before any extraction: no features, no marks. */
    EXPECT(pfe_feature_count(&ex) == 0);
    EXPECT(pfe_feature_get(&ex, 0, &f) == PFE_ERR_INDEX);

    /* A good extraction, then each bad argument. */
    EXPECT(pfe_extract_mm(&ex, &g, ranges, 361, &cfg, NULL) == PFE_OK);
    EXPECT(pfe_feature_count(&ex) == 1);
    EXPECT(pfe_feature_get(&ex, 0, &f) == PFE_OK);
    EXPECT(f.kind == PFE_FEATURE_CIRCLE && fabsf(f.shape.circle.radius - 1500.0f) < 1.0f);
    EXPECT(f.first == 0 && f.last == 360 && f.points == 361);
    EXPECT(pfe_feature_get(&ex, 1, &f) == PFE_ERR_INDEX);
    EXPECT(pfe_feature_get(&ex, 0, NULL) == PFE_ERR_NULL);
    EXPECT(pfe_stats_get(&ex, &st) == PFE_OK);
    EXPECT(st.readings == 361 && st.valid == 361 && st.features == 1 && st.dropped == 0);
    EXPECT(pfe_marks(&ex, NULL, 0, &count) == PFE_OK && count == 2);
    EXPECT(pfe_marks(&ex, marks, 1, &count) == PFE_ERR_BUFFER_TOO_SMALL && count == 2 &&
           marks[0] == 0);
    EXPECT(pfe_marks(&ex, marks, 4, &count) == PFE_OK && count == 2 && marks[0] == 0 &&
           marks[1] == 360);
    EXPECT(pfe_marks(&ex, NULL, 4, &count) == PFE_ERR_NULL);
    EXPECT(pfe_marks(&ex, marks, 4, NULL) == PFE_ERR_NULL);

    EXPECT(pfe_extract_mm(NULL, &g, ranges, 361, &cfg, NULL) == PFE_ERR_NULL);
    EXPECT(pfe_extract_mm(&other, &g, ranges, 361, &cfg, NULL) == PFE_ERR_NOT_INITIALIZED);
    EXPECT(pfe_feature_count(&other) == PFE_ERR_NOT_INITIALIZED);
    EXPECT(pfe_feature_count(NULL) == PFE_ERR_NULL);
    EXPECT(pfe_stats_get(&other, &st) == PFE_ERR_NOT_INITIALIZED);
    EXPECT(pfe_marks(&other, marks, 4, &count) == PFE_ERR_NOT_INITIALIZED);
    EXPECT(pfe_extract_mm(&ex, NULL, ranges, 361, &cfg, NULL) == PFE_ERR_NULL);
    /* A refused call leaves no stale output. */
    EXPECT(pfe_feature_count(&ex) == 0);
    EXPECT(pfe_stats_get(&ex, &st) == PFE_OK && st.readings == 0);
    EXPECT(pfe_marks(&ex, marks, 4, &count) == PFE_OK && count == 0);
    EXPECT(pfe_extract_mm(&ex, &g, NULL, 361, &cfg, NULL) == PFE_ERR_NULL);
    EXPECT(pfe_extract_mm(&ex, &g, NULL, 0, &cfg, NULL) == PFE_OK); /* an empty scan */
    EXPECT(pfe_extract_mm(&ex, &g, (const float *)((const char *)ranges + 1), 10, &cfg, NULL) ==
           PFE_ERR_MISALIGNED);
    EXPECT(pfe_extract_mm(&ex, &g, ranges, 361, NULL, NULL) == PFE_ERR_NULL);
    EXPECT(pfe_extract_mm(&ex, &g, ranges, PFE_MAX_READINGS + 1, &cfg, NULL) ==
           PFE_ERR_TOO_MANY_READINGS);
    EXPECT(pfe_extract_mm(&ex, &g, ranges, (size_t)-1, &cfg, NULL) == PFE_ERR_TOO_MANY_READINGS);

    pfe_geometry bad = g;
    bad.angle_step = NAN;
    EXPECT(pfe_extract_mm(&ex, &bad, ranges, 361, &cfg, NULL) == PFE_ERR_INVALID_GEOMETRY);
    bad = g;
    bad.r_max = 0.0f;
    EXPECT(pfe_extract_mm(&ex, &bad, ranges, 361, &cfg, NULL) == PFE_ERR_INVALID_GEOMETRY);

    pfe_config c2 = cfg;
    c2.sigma_r = NAN;
    EXPECT(pfe_extract_mm(&ex, &g, ranges, 361, &c2, NULL) == PFE_ERR_INVALID_CONFIG);
    EXPECT(pfe_config_check(&c2) == PFE_ERR_INVALID_CONFIG);
    c2 = cfg;
    c2.threshold = 9;
    EXPECT(pfe_extract_mm(&ex, &g, ranges, 361, &c2, NULL) == PFE_ERR_INVALID_CONFIG);
    c2 = cfg;
    c2.scrutiny = 2;
    EXPECT(pfe_extract_mm(&ex, &g, ranges, 361, &c2, NULL) == PFE_ERR_INVALID_CONFIG);
    c2 = cfg;
    c2.min_points = 1;
    EXPECT(pfe_extract_mm(&ex, &g, ranges, 361, &c2, NULL) == PFE_ERR_INVALID_CONFIG);

    pfe_scan_options o2 = opt;
    o2.quantum = NAN;
    EXPECT(pfe_extract_mm(&ex, &g, ranges, 361, &cfg, &o2) == PFE_ERR_INVALID_ARGUMENT);
    o2 = opt;
    o2.quantum = -1.0f;
    EXPECT(pfe_extract_mm(&ex, &g, ranges, 361, &cfg, &o2) == PFE_ERR_INVALID_ARGUMENT);
    o2 = opt;
    o2.has_motion = 1;
    o2.motion.omega = INFINITY;
    EXPECT(pfe_extract_mm(&ex, &g, ranges, 361, &cfg, &o2) == PFE_ERR_INVALID_ARGUMENT);
    o2.has_motion = 3;
    EXPECT(pfe_extract_mm(&ex, &g, ranges, 361, &cfg, &o2) == PFE_ERR_INVALID_ARGUMENT);

    EXPECT(pfe_extract_lms(&ex, &g, codes, 361, 1.0f, &cfg, NULL) == PFE_OK);
    EXPECT(pfe_feature_count(&ex) == 1);
    EXPECT(pfe_extract_lms(&ex, &g, codes, 361, NAN, &cfg, NULL) == PFE_ERR_INVALID_ARGUMENT);
    EXPECT(pfe_extract_lms(&ex, &g, codes, 361, 0.0f, &cfg, NULL) == PFE_ERR_INVALID_ARGUMENT);
    EXPECT(pfe_extract_lms(&ex, &g, codes, 361, -10.0f, &cfg, NULL) ==
           PFE_ERR_INVALID_ARGUMENT);
    EXPECT(pfe_extract_lms(&ex, &g, codes, 361, INFINITY, &cfg, NULL) ==
           PFE_ERR_INVALID_ARGUMENT);
    EXPECT(pfe_extract_lms(&ex, &g, NULL, 361, 1.0f, &cfg, NULL) == PFE_ERR_NULL);

    /* More features than PFE_MAX_FEATURES: a comb of short walls at alternating ranges. */
    float comb[1081];
    pfe_geometry g4;
    EXPECT(pfe_geometry_lms200(270.0f, 0.25f, &g4) == PFE_OK);
    for (int i = 0; i < 1081; i++) {
        comb[i] = (i / 8) % 2 ? 2000.0f : 3000.0f;
    }
    pfe_config paper;
    EXPECT(pfe_config_paper(&paper) == PFE_OK);
    EXPECT(pfe_extract_mm(&ex, &g4, comb, 1081, &paper, NULL) == PFE_ERR_FEATURE_CAPACITY);
    EXPECT(pfe_feature_count(&ex) == PFE_MAX_FEATURES);
    EXPECT(pfe_stats_get(&ex, &st) == PFE_OK && st.features == PFE_MAX_FEATURES &&
           st.dropped > 0);
    EXPECT(pfe_feature_get(&ex, PFE_MAX_FEATURES - 1, &f) == PFE_OK);

    /* Status texts. */
    EXPECT(strcmp(pfe_status_str(PFE_OK), "ok") == 0);
    EXPECT(strstr(pfe_status_str(PFE_ERR_FEATURE_CAPACITY), "dropped") != NULL);
    EXPECT(strcmp(pfe_status_str(12345), "not a pfe status") == 0);

    printf("errors: %d checks, %d failed\n", checks, failures);
    return failures == 0 ? 0 : 1;
}

static void print_result(int status, const char *cfg, const char *path, long id) {
    pfe_stats st;
    pfe_feature f;
    uint16_t marks[PFE_MAX_READINGS];
    size_t count = 0;
    int n = pfe_feature_count(&ex);
    printf("X %ld %s %s %d %d\n", id, cfg, path, status, n);
    if (pfe_stats_get(&ex, &st) != PFE_OK) {
        printf("stats failed\n");
    }
    printf("T %" PRIu32 " %" PRIu32 " %" PRIu32 " %" PRIu32 " %" PRIu32 " %" PRIu32 " %" PRIu32
           " %" PRIu32 " %" PRIu32 " %" PRIu32 "\n",
           st.readings, st.valid, st.segments, st.short_segments, st.degenerate, st.features,
           st.dropped, st.predictions, st.sweeps_aligned, st.scan_sigma_um);
    for (int i = 0; i < n; i++) {
        if (pfe_feature_get(&ex, (size_t)i, &f) != PFE_OK) {
            printf("feature %d failed\n", i);
            continue;
        }
        if (f.kind == PFE_FEATURE_LINE) {
            const pfe_line *l = &f.shape.line;
            printf("L %u %u %u %08" PRIx32 " %08" PRIx32 " %08" PRIx32 " %08" PRIx32
                   " %08" PRIx32 " %08" PRIx32 " %08" PRIx32 " %08" PRIx32 " %08" PRIx32 "\n",
                   f.first, f.last, f.points, bits(l->alpha), bits(l->rho), bits(l->var_alpha),
                   bits(l->var_rho), bits(l->cov_alpha_rho), bits(l->start.x), bits(l->start.y),
                   bits(l->end.x), bits(l->end.y));
        } else if (f.kind == PFE_FEATURE_OBJECT) {
            const pfe_object *o = &f.shape.object;
            printf("O %u %u %u %08" PRIx32 " %08" PRIx32 " %08" PRIx32 " %08" PRIx32
                   " %08" PRIx32 " %08" PRIx32 " %08" PRIx32 "\n",
                   f.first, f.last, f.points, bits(o->center.x), bits(o->center.y),
                   bits(o->cov[0][0]), bits(o->cov[0][1]), bits(o->cov[1][0]),
                   bits(o->cov[1][1]), bits(o->extent));
        } else {
            const pfe_circle *c = &f.shape.circle;
            printf("C %u %u %u %08" PRIx32 " %08" PRIx32 " %08" PRIx32, f.first, f.last,
                   f.points, bits(c->center.x), bits(c->center.y), bits(c->radius));
            for (int r = 0; r < 3; r++) {
                for (int k = 0; k < 3; k++) {
                    printf(" %08" PRIx32, bits(c->cov[r][k]));
                }
            }
            printf(" %08" PRIx32 " %08" PRIx32 "\n", bits(c->start_angle), bits(c->end_angle));
        }
    }
    if (pfe_marks(&ex, marks, PFE_MAX_READINGS, &count) != PFE_OK) {
        printf("marks failed\n");
    }
    printf("M");
    for (size_t i = 0; i < count; i++) {
        printf(" %u", marks[i]);
    }
    printf("\n");
}

static int extract(const char *file) {
    static float ranges[PFE_MAX_READINGS];
    static uint16_t codes[PFE_MAX_READINGS];
    FILE *in = fopen(file, "r");
    if (in == NULL) {
        perror(file);
        return 2;
    }
    if (pfe_extractor_init(&ex, sizeof ex) != PFE_OK) {
        return 2;
    }
    long id;
    uint32_t sigma, sigma_sys, quantum, unit, start, step, r_max, v, omega, beam_dt, sweep_dt;
    unsigned sweeps, has_motion, timing_sweeps;
    size_t n;
    int scans = 0;
    while (fscanf(in, " S %ld %" SCNx32 " %" SCNx32 " %u %" SCNx32 " %" SCNx32 " %" SCNx32 " %" SCNx32
                      " %" SCNx32 " %u %" SCNx32 " %" SCNx32 " %" SCNx32 " %" SCNx32 " %u %zu",
                  &id, &sigma, &sigma_sys, &sweeps, &quantum, &unit, &start, &step, &r_max, &has_motion, &v,
                  &omega, &beam_dt, &sweep_dt, &timing_sweeps, &n) == 16) {
        size_t m;
        if (n > PFE_MAX_READINGS || fscanf(in, " R %zu", &m) != 1 || m != n) {
            fprintf(stderr, "scan %ld: bad R line\n", id);
            return 2;
        }
        for (size_t i = 0; i < n; i++) {
            uint32_t b;
            if (fscanf(in, "%" SCNx32, &b) != 1) {
                return 2;
            }
            ranges[i] = from_bits(b);
        }
        if (fscanf(in, " C %zu", &m) != 1 || m != n) {
            fprintf(stderr, "scan %ld: bad C line\n", id);
            return 2;
        }
        for (size_t i = 0; i < n; i++) {
            unsigned c;
            if (fscanf(in, "%u", &c) != 1) {
                return 2;
            }
            codes[i] = (uint16_t)c;
        }
        pfe_geometry g = {from_bits(start), from_bits(step), from_bits(r_max)};
        pfe_scan_options o;
        pfe_scan_options_default(&o);
        o.sweeps = (uint8_t)sweeps;
        o.has_motion = (uint8_t)has_motion;
        o.motion.v = from_bits(v);
        o.motion.omega = from_bits(omega);
        o.motion.beam_dt = from_bits(beam_dt);
        o.motion.sweep_dt = from_bits(sweep_dt);
        o.motion.sweeps = (uint8_t)timing_sweeps;
        for (int k = 0; k < 2; k++) {
            pfe_config c;
            if (k == 0) {
                pfe_config_paper(&c);
            } else {
                pfe_config_default(&c);
            }
            c.sigma_r = from_bits(sigma);
            c.sigma_sys = from_bits(sigma_sys);
            const char *name = k == 0 ? "paper" : "default";
            /* From mm, with the scan's quantum (as the eval gives it). */
            o.quantum = from_bits(quantum);
            print_result(pfe_extract_mm(&ex, &g, ranges, n, &c, &o), name, "mm", id);
            /* From raw codes, whose unit is their quantum. */
            o.quantum = 0.0f;
            print_result(pfe_extract_lms(&ex, &g, codes, n, from_bits(unit), &c, &o), name,
                         "lms", id);
        }
        scans++;
    }
    if (!feof(in)) {
        fprintf(stderr, "bad input after %d scans\n", scans);
        return 2;
    }
    fclose(in);
    fprintf(stderr, "%d scans\n", scans);
    return 0;
}

int main(int argc, char **argv) {
    if (argc == 2 && strcmp(argv[1], "errors") == 0) {
        return errors();
    }
    if (argc == 3 && strcmp(argv[1], "extract") == 0) {
        return extract(argv[2]);
    }
    fprintf(stderr, "usage: %s errors | extract FILE\n", argv[0]);
    return 2;
}
