/* The segment table (segments.def) behind mocap_segment_* and the sensor-set checks. */
#include "segments.h"

#include <string.h>

typedef struct segment_row {
    int32_t id;
    const char *name;
    int32_t joint;
    int32_t default_node;
} segment_row;

#define MOCAP_SEGMENT_ROW(ENUM, id, name, joint, node) {id, name, joint, node},
static const segment_row SEGMENTS[] = {
#include "segments.def"
};
#undef MOCAP_SEGMENT_ROW

enum { SEGMENT_ROWS = (int)(sizeof SEGMENTS / sizeof SEGMENTS[0]) };

/* A row whose id is not its place, or not the header's enum value, fails the build. */
#define MOCAP_SEGMENT_ROW(ENUM, id, name, joint, node)                                          \
    _Static_assert(MOCAP_SEGMENT_##ENUM == (id), "segments.def: " #ENUM " differs from the header");
#include "segments.def"
#undef MOCAP_SEGMENT_ROW
_Static_assert(SEGMENT_ROWS <= 32, "segment masks are 32 bits");

static int row_ok(int32_t segment) { return segment >= 0 && segment < SEGMENT_ROWS; }

int32_t mocap_segment_count(void) { return SEGMENT_ROWS; }

const char *mocap_segment_name(int32_t segment)
{
    return row_ok(segment) ? SEGMENTS[segment].name : NULL;
}

int32_t mocap_segment_find(const char *name)
{
    if (!name) return -1;
    for (int i = 0; i < SEGMENT_ROWS; i++)
        if (strcmp(SEGMENTS[i].name, name) == 0) return i;
    return -1;
}

int32_t mocap_segment_joint(int32_t segment) { return row_ok(segment) ? SEGMENTS[segment].joint : -1; }

int32_t mocap_segment_default_node(int32_t segment)
{
    return row_ok(segment) ? SEGMENTS[segment].default_node : -1;
}

uint32_t segments_default_set(int32_t segments[MOCAP_MAX_SENSORS], int32_t node_ids[MOCAP_MAX_SENSORS])
{
    uint32_t n = 0;
    for (int i = 0; i < SEGMENT_ROWS && n < MOCAP_MAX_SENSORS; i++) {
        if (SEGMENTS[i].default_node < 0) continue;
        segments[n] = SEGMENTS[i].id;
        node_ids[n] = SEGMENTS[i].default_node;
        n++;
    }
    return n;
}

int segments_index_of(const int32_t *segments, uint32_t count, int32_t segment)
{
    for (uint32_t i = 0; i < count; i++)
        if (segments[i] == segment) return (int)i;
    return -1;
}

const char *segments_name_or(int32_t segment, const char *fallback)
{
    const char *n = mocap_segment_name(segment);
    return n ? n : fallback;
}
