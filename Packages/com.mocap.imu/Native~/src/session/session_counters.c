/* A session's counters by key: the way counters grow without changing mocap_session_stats. */
#include "error.h"
#include "mocap_imu.h"

mocap_status mocap_session_get_counter(mocap_session *session, int32_t counter, uint64_t *out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "out is NULL");
    if (counter < 0 || counter >= MOCAP_SESSION_COUNTER_COUNT)
        return mocap_fail(MOCAP_ERR_UNSUPPORTED, "session counter %d is not known to this library (API %d.%d)",
                          (int)counter, MOCAP_API_VERSION, MOCAP_API_VERSION_MINOR);
    mocap_session_stats stats;
    mocap_status st = mocap_session_get_stats(session, &stats);
    if (st != MOCAP_OK) return st;
    switch ((mocap_session_counter)counter) {
    case MOCAP_SESSION_BYTES_RECEIVED: *out = stats.bytes_received; break;
    case MOCAP_SESSION_FRAMES_DECODED: *out = stats.frames_decoded; break;
    case MOCAP_SESSION_CRC_FAILURES: *out = stats.crc_failures; break;
    case MOCAP_SESSION_BYTES_SKIPPED: *out = stats.bytes_skipped; break;
    case MOCAP_SESSION_UNKNOWN_PACKETS: *out = stats.unknown_packets; break;
    case MOCAP_SESSION_SAMPLES_DECODED: *out = stats.samples_decoded; break;
    case MOCAP_SESSION_SAMPLES_REJECTED: *out = stats.samples_rejected; break;
    case MOCAP_SESSION_FRAMES_EMITTED: *out = stats.frames_emitted; break;
    case MOCAP_SESSION_FRAMES_DROPPED: *out = stats.frames_dropped; break;
    case MOCAP_SESSION_BYTES_DROPPED: *out = stats.bytes_dropped; break;
    case MOCAP_SESSION_RECONNECTS: *out = stats.reconnects; break;
    case MOCAP_SESSION_CAPTURE_BYTES_WRITTEN: *out = stats.capture_bytes_written; break;
    case MOCAP_SESSION_REPLAY_CHUNKS_SKIPPED: *out = stats.replay_chunks_skipped; break;
    case MOCAP_SESSION_REPLAY_TAIL_DAMAGED: *out = stats.replay_tail_damaged ? 1u : 0u; break;
    case MOCAP_SESSION_SENSORS_SEEN_MASK: *out = stats.sensors_seen_mask; break;
    case MOCAP_SESSION_COUNTER_COUNT: break; /* refused above */
    }
    return MOCAP_OK;
}
