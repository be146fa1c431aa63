/* Root integration with contact-based drift correction. The rule is stated in drift.h. */
#include "drift.h"

#include <math.h>
#include <string.h>

void drift_reset(drift_state *s, const double start[3])
{
    memset(s, 0, sizeof *s);
    memcpy(s->root, start, sizeof s->root);
    s->initialized = 1;
}

int drift_step(drift_state *s, const drift_params *p, const double velocity[3],
               const double contact[2], const double foot_rel[2][3], double root_out[3])
{
    double root[3];
    for (int k = 0; k < 3; ++k) root[k] = s->root[k] + velocity[k] * p->dt;
    int now[2] = {contact[0] >= p->contact_threshold, contact[1] >= p->contact_threshold};
    int corrected = 0;

    if (p->enabled) {
        /* 1. Planted feet (in contact now and before) pull the root back by foot_lock of their slip. */
        double dx = 0.0, dz = 0.0;
        int planted = 0;
        for (int f = 0; f < 2; ++f) {
            if (!(now[f] && s->contact[f])) continue;
            dx += s->foot[f][0] - (root[0] + foot_rel[f][0]);
            dz += s->foot[f][2] - (root[2] + foot_rel[f][2]);
            ++planted;
        }
        if (planted > 0) {
            root[0] += p->foot_lock * dx / planted;
            root[2] += p->foot_lock * dz / planted;
            corrected |= fabs(dx) + fabs(dz) > 1e-12;
        }
        /* 2. The lowest foot in contact stands on the floor. */
        double dy = 0.0;
        int touching = 0;
        double lowest_contact = 0.0;
        for (int f = 0; f < 2; ++f) {
            if (!now[f]) continue;
            double sole = root[1] + foot_rel[f][1] - p->foot_height[f];
            if (!touching || sole < lowest_contact) lowest_contact = sole;
            touching = 1;
        }
        if (touching) dy = p->floor_height - lowest_contact;
        /* 3. No sole below the floor. */
        double lowest = INFINITY;
        for (int f = 0; f < 2; ++f) {
            double sole = root[1] + dy + foot_rel[f][1] - p->foot_height[f];
            if (sole < lowest) lowest = sole;
        }
        if (lowest < p->floor_height) dy += p->floor_height - lowest;
        root[1] += dy;
        corrected |= fabs(dy) > 1e-12;
    }

    memcpy(s->root, root, sizeof s->root);
    for (int f = 0; f < 2; ++f) {
        for (int k = 0; k < 3; ++k) s->foot[f][k] = root[k] + foot_rel[f][k];
        s->contact[f] = now[f];
    }
    s->initialized = 1;
    memcpy(root_out, root, sizeof s->root);
    return corrected;
}
