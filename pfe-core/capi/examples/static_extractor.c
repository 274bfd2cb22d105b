/*
 * pfe from C: one extractor in static memory (no allocation), pfe's default configuration,
 * one LMS200 scan (180° at 0.5°, ranges in mm) of a wall 2 m ahead and a pillar, and the
 * features it finds. Build (see README.md):
 *
 *   cargo build -p pfe-capi --release
 *   cc -std=c11 -I pfe-core/capi/include pfe-core/capi/examples/static_extractor.c \
 *      target/release/libpfe_capi.a -lm -lpthread -ldl -o static_extractor
 */
#include <math.h>
#include <stdio.h>

#include "pfe.h"

/* PFE_EXTRACTOR_SIZE bytes in .bss, aligned as the library needs. */
static pfe_extractor extractor;

int main(void) {
    pfe_geometry g;
    pfe_config config;
    float ranges[361];

    if (pfe_extractor_init(&extractor, sizeof extractor) != PFE_OK ||
        pfe_geometry_lms200(180.0f, 0.5f, &g) != PFE_OK || pfe_config_default(&config) != PFE_OK) {
        return 1;
    }
    config.sigma_r = 5.0f; /* the scanner's range noise, mm */

    /* A wall x = 2000 mm, and a pillar of radius 150 mm centred at (1200, 600). */
    for (int i = 0; i < 361; i++) {
        float b = g.start_angle + g.angle_step * (float)i;
        float c = cosf(b), s = sinf(b);
        float r = c > 0.1f ? 2000.0f / c : NAN; /* NaN: no return */
        float p = 1200.0f * c + 600.0f * s;     /* distance along the beam to the centre's foot */
        float d2 = 1200.0f * 1200.0f + 600.0f * 600.0f - p * p;
        if (p > 0.0f && d2 < 150.0f * 150.0f) {
            float hit = p - sqrtf(150.0f * 150.0f - d2);
            if (!(hit >= r)) {
                r = hit;
            }
        }
        ranges[i] = roundf(r); /* an LMS200 in mm mode reports whole millimetres */
    }

    pfe_status status = pfe_extract_mm(&extractor, &g, ranges, 361, &config, NULL);
    if (status != PFE_OK) {
        fprintf(stderr, "pfe_extract_mm: %s\n", pfe_status_str(status));
        return 1;
    }
    int n = pfe_feature_count(&extractor);
    for (int i = 0; i < n; i++) {
        pfe_feature f;
        pfe_feature_get(&extractor, (size_t)i, &f);
        if (f.kind == PFE_FEATURE_LINE) {
            printf("line   beams %3u to %3u: alpha %.4f rad, rho %.1f mm (sd %.2f mm)\n", f.first,
                   f.last, f.shape.line.alpha, f.shape.line.rho, sqrtf(f.shape.line.var_rho));
        } else if (f.kind == PFE_FEATURE_OBJECT) {
            printf("object beams %3u to %3u: centre (%.1f, %.1f) mm, %.0f mm across\n", f.first,
                   f.last, f.shape.object.center.x, f.shape.object.center.y,
                   f.shape.object.extent);
        } else {
            printf("circle beams %3u to %3u: centre (%.1f, %.1f) mm, radius %.1f mm\n", f.first,
                   f.last, f.shape.circle.center.x, f.shape.circle.center.y,
                   f.shape.circle.radius);
        }
    }
    return 0;
}
