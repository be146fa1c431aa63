/* Streaming decoder for the HiPNUC serial protocol (frame: 5A A5 len16 crc16 payload).
 * Fixed-size state, no allocation: feed it any chunks of bytes; it calls back once per frame
 * with a valid CRC. Garbage, bad CRCs and impossible lengths are skipped and counted, and the
 * decoder rescans from the byte after a rejected sync so that no intact frame is lost. */
#ifndef MOCAP_HIPNUC_DECODER_H
#define MOCAP_HIPNUC_DECODER_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HIPNUC_SYNC0 0x5A
#define HIPNUC_SYNC1 0xA5
#define HIPNUC_HEADER_SIZE 6
#define HIPNUC_IMUSOL_SIZE 76          /* 0x91 block */
#define HIPNUC_GWSOL_HEADER_SIZE 8     /* 0x62 header before the 0x91 blocks */
#define HIPNUC_MAX_NODES 32            /* nodes in one 0x62 packet we can hold (>= 16) */
/* Largest payload accepted; a longer length field is impossible and triggers a resync. */
#define HIPNUC_MAX_PAYLOAD (HIPNUC_GWSOL_HEADER_SIZE + HIPNUC_MAX_NODES * HIPNUC_IMUSOL_SIZE)

/* Packet tags. */
enum {
    HIPNUC_TAG_IMUSOL = 0x91,
    HIPNUC_TAG_GWSOL = 0x62,
    HIPNUC_TAG_ID = 0x90,
    HIPNUC_TAG_ACC = 0xA0,
    HIPNUC_TAG_GYR = 0xB0,
    HIPNUC_TAG_MAG = 0xC0,
    HIPNUC_TAG_EULER = 0xD0,
    HIPNUC_TAG_QUAT = 0xD1,
    HIPNUC_TAG_PRESSURE = 0xF0
};

/* Layout of the bytes after the 0x91 tag (values match mocap_imusol_layout). */
enum {
    HIPNUC_LAYOUT_AUTO = 0,
    HIPNUC_LAYOUT_NODE_ID = 1,
    HIPNUC_LAYOUT_STATUS_WORD = 2
};

/* Which fields of a sample were present in the packet. */
enum {
    HIPNUC_FIELD_NODE_ID = 1u << 0,
    HIPNUC_FIELD_TIME = 1u << 1,
    HIPNUC_FIELD_ACC = 1u << 2,
    HIPNUC_FIELD_GYR = 1u << 3,
    HIPNUC_FIELD_MAG = 1u << 4,
    HIPNUC_FIELD_EULER = 1u << 5,
    HIPNUC_FIELD_QUAT = 1u << 6,
    HIPNUC_FIELD_STATUS = 1u << 7,      /* status word + temperature (newer 0x91 firmware) */
    HIPNUC_FIELD_PRESSURE = 1u << 8
};

/* One sensor's values exactly as the device reports them (device units). */
typedef struct hipnuc_sample {
    uint32_t fields;        /* HIPNUC_FIELD_* */
    uint32_t node_id;
    uint32_t time_ms;
    uint16_t status;        /* newer firmware status bits */
    int8_t temperature_c;
    uint8_t source_tag;     /* 0x91, 0x62 (block of a gateway packet) or 0x90..0xF0 chain */
    float pressure_pa;
    float acc_g[3];
    float gyr_dps[3];
    float mag_ut[3];        /* legacy 0xC0 reports Gauss*1000; converted to uT */
    float euler_deg[3];     /* roll, pitch, yaw */
    float quat[4];          /* w, x, y, z: sensor -> world */
} hipnuc_sample;

/* Everything one valid frame carried. */
typedef struct hipnuc_frame {
    uint16_t payload_length;
    uint8_t first_tag;
    uint8_t gateway_id;     /* 0x62 only */
    uint32_t sample_count;
    hipnuc_sample samples[HIPNUC_MAX_NODES];
} hipnuc_frame;

typedef struct hipnuc_stats {
    uint64_t bytes_in;
    uint64_t frames_ok;        /* CRC-valid frames */
    uint64_t crc_failures;
    uint64_t bytes_skipped;    /* bytes discarded while looking for a sync */
    uint64_t bad_lengths;      /* length field 0 or > HIPNUC_MAX_PAYLOAD */
    uint64_t unknown_tags;     /* CRC-valid payloads (or chain items) with an unknown tag */
    uint64_t truncated_packets;/* a packet claims more bytes than the payload holds */
    uint64_t node_overflows;   /* 0x62 with more nodes than HIPNUC_MAX_NODES */
    uint64_t samples;          /* samples delivered */
} hipnuc_stats;

typedef void (*hipnuc_frame_fn)(void *user, const hipnuc_frame *frame);

typedef struct hipnuc_decoder {
    int layout;                /* HIPNUC_LAYOUT_* */
    size_t length;             /* bytes buffered */
    hipnuc_stats stats;
    hipnuc_frame frame;        /* reused for every callback */
    uint8_t buffer[HIPNUC_HEADER_SIZE + HIPNUC_MAX_PAYLOAD];
} hipnuc_decoder;

void hipnuc_decoder_init(hipnuc_decoder *decoder, int layout);
void hipnuc_decoder_reset(hipnuc_decoder *decoder); /* drop buffered bytes, keep stats/layout */
/* Consume len bytes; on_frame is called synchronously for each valid frame (may be NULL). */
void hipnuc_decoder_feed(hipnuc_decoder *decoder, const uint8_t *data, size_t len,
                         hipnuc_frame_fn on_frame, void *user);

/* End of input (a replay finished, a device closed): no more bytes will complete the pending
 * candidate, so give up on it and decode any whole frames buffered behind it (after a corrupted
 * length field the decoder may be holding intact frames while it waits). Leaves the buffer empty;
 * the abandoned bytes count as skipped. */
void hipnuc_decoder_flush(hipnuc_decoder *decoder, hipnuc_frame_fn on_frame, void *user);

/* Parse one CRC-checked payload into out. Returns the number of samples (>= 0); unknown tags and
 * truncated packets are counted in stats (may be NULL) and parsing stops there. */
int hipnuc_parse_payload(const uint8_t *payload, size_t len, int layout, hipnuc_frame *out,
                         hipnuc_stats *stats);

/* ---- Encoding, for the generator and tests ---- */
/* Wrap a payload into a complete frame (sync, length, CRC). Returns the frame size, or 0 if
 * cap is too small or len > HIPNUC_MAX_PAYLOAD. */
size_t hipnuc_encode_frame(const uint8_t *payload, size_t len, uint8_t *out, size_t cap);
/* Write one 76-byte 0x91 block for sample s in the given layout (NODE_ID or STATUS_WORD). */
void hipnuc_encode_imusol(const hipnuc_sample *s, int layout, uint8_t out[HIPNUC_IMUSOL_SIZE]);
/* Write a 0x62 payload holding n samples (node ids from the samples). Returns its size, or 0 if
 * it does not fit in cap. */
size_t hipnuc_encode_gwsol(uint8_t gateway_id, const hipnuc_sample *samples, uint32_t n,
                           uint8_t *out, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
