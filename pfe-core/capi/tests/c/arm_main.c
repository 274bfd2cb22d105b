/*
 * The smallest program that uses the library on a Cortex-M4F: for the Arm link and its size
 * (tests/arm.rs). A static extractor, the default configuration, one scan of a round room.
 */
#include "pfe.h"

static pfe_extractor extractor;
static float ranges[361];

int main(void) {
    pfe_geometry g;
    pfe_config config;
    if (pfe_extractor_init(&extractor, sizeof extractor) != PFE_OK ||
        pfe_geometry_lms200(180.0f, 0.5f, &g) != PFE_OK || pfe_config_default(&config) != PFE_OK) {
        return -100;
    }
    for (int i = 0; i < 361; i++) {
        ranges[i] = 1500.0f;
    }
    pfe_status status = pfe_extract_mm(&extractor, &g, ranges, 361, &config, NULL);
    return status == PFE_OK ? pfe_feature_count(&extractor) : status;
}
