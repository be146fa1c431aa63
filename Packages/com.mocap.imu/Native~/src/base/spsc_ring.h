/* Lock-free single-producer single-consumer ring of fixed-size elements, and a triple buffer
 * that always hands the consumer the newest value. Storage is allocated once at init. */
#ifndef MOCAP_SPSC_RING_H
#define MOCAP_SPSC_RING_H

#include <stddef.h>
#include <stdint.h>
#include "platform.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct spsc_ring {
    uint8_t *storage;
    size_t element_size;
    uint64_t capacity;          /* power of two */
    mocap_atomic_u64 head;      /* next slot to write (producer) */
    mocap_atomic_u64 tail;      /* next slot to read (consumer) */
} spsc_ring;

/* capacity is rounded up to a power of two. Returns 0 or -1 (no memory). */
int spsc_ring_init(spsc_ring *r, size_t element_size, size_t capacity);
void spsc_ring_destroy(spsc_ring *r);
/* Producer: copy one element in. Returns 0, or -1 when full (nothing written). */
int spsc_ring_push(spsc_ring *r, const void *element);
/* Producer: reserve the next slot to write in place; commit with spsc_ring_commit. NULL if full. */
void *spsc_ring_reserve(spsc_ring *r);
void spsc_ring_commit(spsc_ring *r);
/* Consumer: copy the oldest element out. Returns 0, or -1 when empty. */
int spsc_ring_pop(spsc_ring *r, void *element);
/* Consumer: pointer to the oldest element without removing it (NULL if empty); then release. */
const void *spsc_ring_peek(spsc_ring *r);
void spsc_ring_release(spsc_ring *r);
size_t spsc_ring_size(spsc_ring *r);

/* Triple buffer: the producer publishes whole values, the consumer takes the newest. */
typedef struct triple_buffer {
    uint8_t *storage;          /* 3 slots */
    size_t element_size;
    int back;                  /* producer's slot */
    int front;                 /* consumer's slot */
    mocap_atomic_int middle;   /* slot index | 4 when it holds an unread value */
} triple_buffer;

int triple_buffer_init(triple_buffer *b, size_t element_size);
void triple_buffer_destroy(triple_buffer *b);
/* Producer: slot to fill, then publish. */
void *triple_buffer_write_slot(triple_buffer *b);
void triple_buffer_publish(triple_buffer *b);
/* Consumer: newest published value, or NULL if nothing new since the last call. */
const void *triple_buffer_take(triple_buffer *b);

#ifdef __cplusplus
}
#endif
#endif
