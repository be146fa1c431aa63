/* Lock-free SPSC ring and triple buffer.
 *
 * Ring: head and tail only ever increase (u64 never wraps in practice), so full is
 * head - tail == capacity and empty is head == tail with no wasted slot; the slot is the index
 * masked by capacity - 1. Each side writes only its own index and publishes it with a release
 * store after touching the slot; the other side reads it with an acquire load before touching
 * the slot, which orders the element copy against the index update in both directions. */
#include "spsc_ring.h"

#include <stdlib.h>
#include <string.h>

#include "error.h"

/* Keeps capacity * element_size and the power-of-two rounding far from overflow. */
#define SPSC_MAX_CAPACITY ((size_t)1 << 30)

int spsc_ring_init(spsc_ring *r, size_t element_size, size_t capacity)
{
    memset(r, 0, sizeof(*r));
    if (element_size == 0 || capacity > SPSC_MAX_CAPACITY) {
        (void)mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                         "spsc ring: bad size (element %zu bytes, capacity %zu)", element_size,
                         capacity);
        return -1;
    }
    size_t cap = 1;
    while (cap < capacity)
        cap <<= 1;
    if (element_size > SIZE_MAX / cap) {
        (void)mocap_fail(MOCAP_ERR_NO_MEMORY, "spsc ring: %zu x %zu bytes overflows", cap,
                         element_size);
        return -1;
    }
    r->storage = (uint8_t *)calloc(cap, element_size);
    if (!r->storage) {
        (void)mocap_fail(MOCAP_ERR_NO_MEMORY, "spsc ring: cannot allocate %zu x %zu bytes", cap,
                         element_size);
        return -1;
    }
    r->element_size = element_size;
    r->capacity = cap;
    mocap_atomic_store_u64(&r->head, 0);
    mocap_atomic_store_u64(&r->tail, 0);
    return 0;
}

void spsc_ring_destroy(spsc_ring *r)
{
    free(r->storage);
    r->storage = NULL;
    r->element_size = 0;
    r->capacity = 0;
}

static uint8_t *ring_slot(const spsc_ring *r, uint64_t index)
{
    return r->storage + (size_t)(index & (r->capacity - 1)) * r->element_size;
}

void *spsc_ring_reserve(spsc_ring *r)
{
    const uint64_t head = mocap_atomic_load_u64(&r->head);
    const uint64_t tail = mocap_atomic_load_u64(&r->tail);
    if (head - tail >= r->capacity)
        return NULL;
    return ring_slot(r, head);
}

void spsc_ring_commit(spsc_ring *r)
{
    /* Only the producer writes head, so load + store is a safe increment. */
    mocap_atomic_store_u64(&r->head, mocap_atomic_load_u64(&r->head) + 1);
}

int spsc_ring_push(spsc_ring *r, const void *element)
{
    void *slot = spsc_ring_reserve(r);
    if (!slot)
        return -1;
    memcpy(slot, element, r->element_size);
    spsc_ring_commit(r);
    return 0;
}

const void *spsc_ring_peek(spsc_ring *r)
{
    const uint64_t tail = mocap_atomic_load_u64(&r->tail);
    const uint64_t head = mocap_atomic_load_u64(&r->head);
    if (head == tail)
        return NULL;
    return ring_slot(r, tail);
}

void spsc_ring_release(spsc_ring *r)
{
    mocap_atomic_store_u64(&r->tail, mocap_atomic_load_u64(&r->tail) + 1);
}

int spsc_ring_pop(spsc_ring *r, void *element)
{
    const void *slot = spsc_ring_peek(r);
    if (!slot)
        return -1;
    memcpy(element, slot, r->element_size);
    spsc_ring_release(r);
    return 0;
}

size_t spsc_ring_size(spsc_ring *r)
{
    /* Tail first: head can only have grown since, so the difference is never negative. It can
     * briefly exceed capacity if both sides moved between the loads, hence the clamp. */
    const uint64_t tail = mocap_atomic_load_u64(&r->tail);
    const uint64_t head = mocap_atomic_load_u64(&r->head);
    const uint64_t n = head - tail;
    return (size_t)(n > r->capacity ? r->capacity : n);
}

/* Triple buffer. The three slot indices are always a permutation of {0, 1, 2} split between the
 * producer (back), the shared middle and the consumer (front). Swapping through one atomic
 * exchange means neither side ever waits for the other, and a slot is never owned by both. */
#define TB_FRESH 4
#define TB_INDEX 3

int triple_buffer_init(triple_buffer *b, size_t element_size)
{
    memset(b, 0, sizeof(*b));
    if (element_size == 0 || element_size > SIZE_MAX / 3) {
        (void)mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "triple buffer: bad element size %zu",
                         element_size);
        return -1;
    }
    b->storage = (uint8_t *)calloc(3, element_size);
    if (!b->storage) {
        (void)mocap_fail(MOCAP_ERR_NO_MEMORY, "triple buffer: cannot allocate 3 x %zu bytes",
                         element_size);
        return -1;
    }
    b->element_size = element_size;
    b->back = 0;
    b->front = 2;
    mocap_atomic_store_int(&b->middle, 1);
    return 0;
}

void triple_buffer_destroy(triple_buffer *b)
{
    free(b->storage);
    b->storage = NULL;
    b->element_size = 0;
}

void *triple_buffer_write_slot(triple_buffer *b)
{
    return b->storage + (size_t)b->back * b->element_size;
}

void triple_buffer_publish(triple_buffer *b)
{
    /* Release hands the filled slot over; acquire on the slot we get back makes sure the
     * consumer's last reads of it are finished before we overwrite it. An unread value in the
     * middle is simply dropped: the consumer wants the newest, not every one. */
    const int old = mocap_atomic_exchange_int(&b->middle, b->back | TB_FRESH);
    b->back = old & TB_INDEX;
}

const void *triple_buffer_take(triple_buffer *b)
{
    if (!(mocap_atomic_load_int(&b->middle) & TB_FRESH))
        return NULL;
    /* Only the producer can change middle meanwhile, and only to another fresh value, so the
     * exchange always yields a fresh slot. */
    const int old = mocap_atomic_exchange_int(&b->middle, b->front);
    b->front = old & TB_INDEX;
    return b->storage + (size_t)b->front * b->element_size;
}
