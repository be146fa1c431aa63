/* --sensors and the model's optional sensors (sensor_set.h). */
#include "sensor_set.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_args.h"

/* The table's names, for an error that has to say which are known. */
static void known_segments(char *out, size_t cap)
{
    size_t used = 0;
    out[0] = '\0';
    for (int32_t s = 0; s < mocap_segment_count() && used < cap; ++s) {
        int n = snprintf(out + used, cap - used, "%s%s", s ? ", " : "", mocap_segment_name(s));
        if (n < 0) break;
        used += (size_t)n;
    }
}

int sensor_set_parse(const char *list, mocap_session_config *cfg, char *why, size_t why_cap)
{
    mocap_session_config set = *cfg;
    set.sensor_count = 0;
    set.optional_mask = 0;
    const char *p = list;
    if (!p || !*p) {
        snprintf(why, why_cap, "the list is empty");
        return -1;
    }
    for (;;) {
        const char *end = strchr(p, ',');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        char entry[64];
        if (len == 0 || len >= sizeof entry) {
            snprintf(why, why_cap, "'%.*s' is not SEGMENT=NODE", (int)(len < 40 ? len : 40), p);
            return -1;
        }
        memcpy(entry, p, len);
        entry[len] = '\0';
        int optional = 0;
        if (entry[len - 1] == '?') {
            optional = 1;
            entry[--len] = '\0';
        }
        char *equals = strchr(entry, '=');
        if (!equals || equals == entry || equals[1] == '\0') {
            snprintf(why, why_cap, "'%s' is not SEGMENT=NODE", entry);
            return -1;
        }
        *equals = '\0';
        const char *node_text = equals + 1;
        const int32_t segment = mocap_segment_find(entry);
        if (segment < 0) {
            char known[256];
            known_segments(known, sizeof known);
            snprintf(why, why_cap, "unknown segment '%s' (known: %s)", entry, known);
            return -1;
        }
        char *node_end = NULL;
        errno = 0;
        long node = strtol(node_text, &node_end, 10);
        if (node_end == node_text || *node_end != '\0' || errno == ERANGE || node < 0 || node > 255) {
            snprintf(why, why_cap, "node '%s' of %s is not a node id 0..255", node_text, entry);
            return -1;
        }
        for (uint32_t i = 0; i < set.sensor_count; ++i) {
            if (set.sensor_segments[i] == segment) {
                snprintf(why, why_cap, "segment %s is listed twice", entry);
                return -1;
            }
            if (set.node_ids[i] == (int32_t)node) {
                snprintf(why, why_cap, "node %ld is given to both %s and %s", node,
                         mocap_segment_name(set.sensor_segments[i]), entry);
                return -1;
            }
        }
        if (set.sensor_count == MOCAP_MAX_SENSORS) {
            snprintf(why, why_cap, "more than %d sensors", MOCAP_MAX_SENSORS);
            return -1;
        }
        set.sensor_segments[set.sensor_count] = segment;
        set.node_ids[set.sensor_count] = (int32_t)node;
        if (optional) set.optional_mask |= 1u << set.sensor_count;
        set.sensor_count++;
        if (!end) break;
        p = end + 1;
    }
    *cfg = set;
    return 0;
}

int sensor_set_from_args(int argc, char **argv, mocap_session_config *cfg)
{
    const char *list = cli_value(argc, argv, "--sensors");
    if (!list) return 0;
    char why[512];
    if (sensor_set_parse(list, cfg, why, sizeof why) != 0) {
        fprintf(stderr, "mocapctl: --sensors %s: %s\n", list, why);
        return 2;
    }
    return 0;
}

void sensor_set_apply_model(mocap_session_config *cfg, const mocap_model_info *info)
{
    for (uint32_t i = 0; i < cfg->sensor_count && i < MOCAP_MAX_SENSORS; ++i) {
        int required = 0;
        for (uint32_t k = 0; k < info->sensor_count && k < MOCAP_MAX_SENSORS; ++k)
            if (info->sensor_segments[k] == cfg->sensor_segments[i])
                required = (info->sensor_required_mask >> k) & 1u;
        if (!required) cfg->optional_mask |= 1u << i;
    }
}

void sensor_set_describe(const mocap_session_config *cfg, char *out, size_t cap)
{
    size_t used = 0;
    out[0] = '\0';
    for (uint32_t i = 0; i < cfg->sensor_count && used < cap; ++i) {
        int n = snprintf(out + used, cap - used, "%s%s=%d%s", i ? "," : "",
                         mocap_segment_name(cfg->sensor_segments[i]), (int)cfg->node_ids[i],
                         (cfg->optional_mask >> i) & 1u ? "?" : "");
        if (n < 0) break;
        used += (size_t)n;
    }
}
