/*
 * mocap_imu.h: public C API of the com.mocap.imu engine.
 *
 * The engine turns HiPNUC inertial sensor byte streams (USB serial, HID, or a recorded capture)
 * into synchronised, calibrated bone orientations and accelerations in the model frame
 * (right-handed, Y up, character facing +Z at calibration, metres, seconds).
 *
 * Conventions
 *  - Every function that can fail returns mocap_status. MOCAP_OK is 0; anything else is an error
 *    whose human-readable text mocap_last_error() returns on the same thread.
 *  - Handles are opaque. Only fixed-width, blittable types cross this boundary, so the structs
 *    can be mirrored 1:1 from C# (see mocap_struct_layout()).
 *  - Quaternions are (w, x, y, z). Rotation matrices are row-major float[9].
 *  - Thread safety is stated per function. "Any thread" means the call may race with other calls
 *    on the same session from other threads; "one thread" means the caller serialises calls.
 *
 * Versioning: major.minor. MOCAP_API_VERSION is the major version: it changes when a signature, a
 * struct layout or the meaning of a value changes, and a binding must refuse a library of another
 * major. A minor version (MOCAP_API_VERSION_MINOR) only adds: functions, enum values and counter
 * keys (mocap_session_get_counter, mocap_solver_get_counter); existing structs never grow within
 * a major, so new counters are keys. A binding built for M.m therefore accepts any library M.n with
 * n >= m. mocap_api_version() and mocap_api_version_minor() return what the library was built with.
 */
#ifndef MOCAP_IMU_H
#define MOCAP_IMU_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32) && defined(MOCAP_STATIC)
/* Linked statically into the program (mocapctl, the tests): no DLL import thunks. */
#  define MOCAP_API
#elif defined(_WIN32)
#  if defined(MOCAP_BUILDING_LIBRARY)
#    define MOCAP_API __declspec(dllexport)
#  else
#    define MOCAP_API __declspec(dllimport)
#  endif
#elif defined(__GNUC__)
#  define MOCAP_API __attribute__((visibility("default")))
#else
#  define MOCAP_API
#endif

#define MOCAP_API_VERSION 6
#define MOCAP_API_VERSION_MINOR 6
/* The most sensors one session (one character) carries: a HiPNUC gateway's limit. A session's
 * own count comes from its config; no array below is filled beyond it. */
#define MOCAP_MAX_SENSORS 16
#define MOCAP_PATH_MAX 260

/* ------------------------------------------------------------------------------------------ */
/* Status codes                                                                                */
/* ------------------------------------------------------------------------------------------ */
typedef int32_t mocap_status;
enum {
    MOCAP_OK = 0,
    MOCAP_ERR_INVALID_ARGUMENT = 1, /* a NULL pointer, an out-of-range value, a bad config */
    MOCAP_ERR_NOT_FOUND = 2,        /* port, device or file does not exist */
    MOCAP_ERR_PERMISSION = 3,       /* the OS refused access (e.g. not in the dialout group) */
    MOCAP_ERR_IO = 4,               /* read/write failed; disk full; device error */
    MOCAP_ERR_DISCONNECTED = 5,     /* the device went away (unplugged) */
    MOCAP_ERR_FORMAT = 6,           /* a file is not what it claims (bad magic, CRC, version) */
    MOCAP_ERR_STATE = 7,            /* the call is not valid in the session's current state */
    MOCAP_ERR_UNSUPPORTED = 8,      /* feature not compiled in or not available on this OS */
    MOCAP_ERR_NO_MEMORY = 9,
    MOCAP_ERR_BAD_CALIBRATION = 10, /* calibration refused: see mocap_calibration_report */
    MOCAP_ERR_NO_DATA = 11,         /* nothing new to return (not a failure for polling) */
    MOCAP_ERR_END_OF_STREAM = 12,   /* a replay has delivered everything */
    MOCAP_ERR_TIMEOUT = 13
};

/* Text of the last error raised on the calling thread (never NULL; "" when none).
 * Thread safety: any thread; the text is thread-local and valid until the next failing call. */
MOCAP_API const char *mocap_last_error(void);

/* Short constant name of a status code, e.g. "MOCAP_ERR_NOT_FOUND". Any thread. */
MOCAP_API const char *mocap_status_name(mocap_status status);

/* MOCAP_API_VERSION (the major version) of the built library. Any thread. */
MOCAP_API int32_t mocap_api_version(void);
/* MOCAP_API_VERSION_MINOR of the built library (absent before 5.1: read a missing symbol as 0). */
MOCAP_API int32_t mocap_api_version_minor(void);

/* "major.minor.patch" of the engine. Any thread. */
MOCAP_API const char *mocap_version_string(void);

/* ------------------------------------------------------------------------------------------ */
/* Body segments and sensor data                                                               */
/* ------------------------------------------------------------------------------------------ */
/* Body segments a sensor can ride on: one table in the engine (src/imu/segments.def) gives each
 * its name, the SMPL joint whose bone it follows and its node id in the default sensor set.
 * Bindings read the table through the functions below instead of copying it; values are only
 * ever added (a minor version). */
typedef enum mocap_segment {
    MOCAP_SEGMENT_PELVIS = 0,
    MOCAP_SEGMENT_LEFT_WRIST = 1,
    MOCAP_SEGMENT_RIGHT_WRIST = 2,
    MOCAP_SEGMENT_LEFT_SHIN = 3,
    MOCAP_SEGMENT_RIGHT_SHIN = 4,
    MOCAP_SEGMENT_HEAD = 5,
    MOCAP_SEGMENT_CHEST = 6
} mocap_segment;

/* Number of segments in the table (the valid values are 0 .. count-1). Any thread. */
MOCAP_API int32_t mocap_segment_count(void);
/* Name such as "pelvis", "left_wrist". Any thread. NULL for an invalid segment. */
MOCAP_API const char *mocap_segment_name(int32_t segment);
/* The segment called name (exact, lower case), or -1. Any thread. */
MOCAP_API int32_t mocap_segment_find(const char *name);
/* The SMPL-24 joint (contract order) whose bone the segment's sensor follows, or -1. Any thread. */
MOCAP_API int32_t mocap_segment_joint(int32_t segment);
/* The segment's node id in the default sensor set (mocap_config_defaults), or -1 when the
 * default set leaves it out. Any thread. */
MOCAP_API int32_t mocap_segment_default_node(int32_t segment);

/* Per-sensor flags in mocap_sensor_frame.flags. */
enum {
    MOCAP_SENSOR_VALID = 1u << 0,        /* has ever produced a sample; values are meaningful */
    MOCAP_SENSOR_HELD = 1u << 1,         /* no sample bracketed this frame: last value held */
    MOCAP_SENSOR_STALE = 1u << 2,        /* last sample older than stale_after_s */
    MOCAP_SENSOR_CALIBRATED = 1u << 3,   /* bone_* fields use a calibration */
    MOCAP_SENSOR_EXTRAPOLATED = 1u << 4  /* reserved */
};

/* What a sensor gave one frame (mocap_sensor_frame.state); the flags above say the same in bits. */
typedef enum mocap_sensor_state {
    MOCAP_SENSOR_FRESH = 0,  /* samples bracketed the frame time: interpolated */
    MOCAP_SENSOR_HOLDING = 1,/* no sample after the frame time yet: the last value is held */
    MOCAP_SENSOR_SILENT = 2, /* nothing for longer than stale_after_s: the held value is old */
    MOCAP_SENSOR_ABSENT = 3  /* never sent a sample: the values are placeholders */
} mocap_sensor_state;

/* One sensor in one output frame. All vectors in SI units. */
typedef struct mocap_sensor_frame {
    /* Calibrated bone orientation, bone -> model frame, quaternion (w,x,y,z). Before calibration
     * it is the sensor's own orientation mapped upright into the model frame (a preview, with
     * MOCAP_SENSOR_CALIBRATED clear); identity for a sensor that never sent data. */
    float bone_orientation[4];
    /* Bone-attached linear acceleration in the model frame, gravity and offset removed, m/s^2
     * (zero before calibration). */
    float bone_acceleration[3];
    /* Raw sensor orientation, sensor -> sensor world frame (Z up; NWU or ENU), after validation. */
    float sensor_orientation[4];
    /* Specific force in the sensor world frame, Kalman filtered, m/s^2 (about +9.81 on Z at rest). */
    float world_specific_force[3];
    /* Angular rate in the sensor frame, rad/s. */
    float angular_rate[3];
    /* Seconds since this sensor's newest sample, at the frame time (negative never). */
    float age_s;
    uint32_t flags;  /* MOCAP_SENSOR_* */
    uint32_t node_id;
    int32_t segment; /* mocap_segment the sensor rides on (from the session config) */
    int32_t state;   /* mocap_sensor_state */
} mocap_sensor_frame;

/* Frame flags in mocap_frame.flags. */
enum {
    MOCAP_FRAME_CALIBRATED = 1u << 0, /* every required (not optional) sensor has a calibration */
    MOCAP_FRAME_COMPLETE = 1u << 1    /* every sensor had a fresh sample bracketing the frame */
};

/* One synchronised output frame at the session's output rate. */
typedef struct mocap_frame {
    uint64_t sequence;         /* 0, 1, 2 ... per session; gaps mean frames were dropped */
    double time_s;             /* frame time on the session clock (seconds) */
    int64_t newest_receive_ns; /* receive time of the newest bytes that fed this frame */
    int64_t emitted_ns;        /* session clock when the frame was produced (latency = diff) */
    uint32_t flags;            /* MOCAP_FRAME_* */
    uint32_t fresh_mask;       /* bit i set: sensors[i] had a fresh sample for this frame */
    uint32_t sensor_count;     /* the session's sensors, in its config order; the rest are zero */
    uint32_t reserved;
    mocap_sensor_frame sensors[MOCAP_MAX_SENSORS];
} mocap_frame;

/* ------------------------------------------------------------------------------------------ */
/* Session configuration                                                                       */
/* ------------------------------------------------------------------------------------------ */
typedef enum mocap_source_kind {
    MOCAP_SOURCE_SERIAL = 0,  /* path = port, e.g. "/dev/ttyUSB0" or "COM3" */
    MOCAP_SOURCE_HID = 1,     /* hid_vendor_id/hid_product_id, or path = hidraw path */
    MOCAP_SOURCE_REPLAY = 2   /* path = capture file written by the engine */
} mocap_source_kind;

typedef enum mocap_imusol_layout {
    MOCAP_IMUSOL_AUTO = 0,        /* decide per packet when unambiguous, else node id layout */
    MOCAP_IMUSOL_NODE_ID = 1,     /* older firmware: byte 1 is the node id */
    MOCAP_IMUSOL_STATUS_WORD = 2  /* newer firmware: bytes 1..2 status, 3 temperature, 4..7 Pa */
} mocap_imusol_layout;

typedef enum mocap_world_frame {
    MOCAP_WORLD_NWU = 0,  /* X north, Y west, Z up (HI221 manual) */
    MOCAP_WORLD_ENU = 1   /* X east, Y north, Z up (newer SDK default) */
} mocap_world_frame;

typedef struct mocap_session_config {
    uint32_t struct_size;     /* sizeof(mocap_session_config): lets the library check the caller */
    int32_t source_kind;      /* mocap_source_kind */
    char path[MOCAP_PATH_MAX];/* port, hidraw path or capture file (UTF-8, NUL-terminated) */
    uint32_t baud;            /* serial only; any rate the OS accepts (default 460800) */
    uint16_t hid_vendor_id;   /* HID only, when path is empty */
    uint16_t hid_product_id;
    /* The sensor set: sensor i rides on segment sensor_segments[i] and sends as HiPNUC node
     * node_ids[i] (0..255). Frames, calibration and reports list the sensors in this order.
     * Each segment and node id at most once. */
    uint32_t sensor_count;    /* 1 .. MOCAP_MAX_SENSORS (default: the default set, 6) */
    int32_t sensor_segments[MOCAP_MAX_SENSORS]; /* mocap_segment */
    int32_t node_ids[MOCAP_MAX_SENSORS];
    /* bit i: sensor i may be missing. Calibration leaves a missing optional sensor out instead of
     * refusing, and MOCAP_FRAME_CALIBRATED does not wait for it. Set it from the model's optional
     * sensors (mocap_model_info.sensor_required_mask). Default 0. */
    uint32_t optional_mask;
    int32_t imusol_layout;    /* mocap_imusol_layout */
    int32_t world_frame;      /* mocap_world_frame: only used before calibration, see docs */
    float output_rate_hz;     /* output frame rate (default 60) */
    float hold_latency_s;     /* wait this long for late sensors before holding (default 0.05) */
    float stale_after_s;      /* a sensor is stale after this long without data (default 0.25) */
    float kalman_process_noise;     /* acceleration random-walk spectral density (m/s^3)^2/Hz */
    float kalman_measurement_noise; /* accelerometer noise variance (m/s^2)^2 */
    int32_t replay_realtime;  /* replay: 0 = as fast as possible, 1 = at recorded pace */
    float replay_speed;       /* replay_realtime: pace multiplier (default 1) */
    int32_t auto_reconnect;   /* serial/HID: reopen after an unplug (default 1) */
    char capture_path[MOCAP_PATH_MAX]; /* if non-empty, record the raw byte stream here */
} mocap_session_config;

/* Fill a config with defaults (struct_size set, 460800 baud, the default sensor set in segment
 * order with each segment's default node id, 60 Hz ...).
 * Any thread. */
MOCAP_API mocap_status mocap_config_defaults(mocap_session_config *config);

/* ------------------------------------------------------------------------------------------ */
/* Session                                                                                     */
/* ------------------------------------------------------------------------------------------ */
typedef struct mocap_session mocap_session;

/* Validate the config and open the source (the port, device or file). No thread runs yet, so
 * calibration can be loaded or scheduled before mocap_session_start(). On failure *out is NULL
 * and mocap_last_error() names the port/file and the cause. One thread. */
MOCAP_API mocap_status mocap_session_open(const mocap_session_config *config, mocap_session **out);

/* Start the reader and processing threads. One thread. */
MOCAP_API mocap_status mocap_session_start(mocap_session *session);

/* Stop all threads (even while a device read blocks), then flush and close a capture being
 * recorded. Returns MOCAP_OK, or the recording's failure (a full disk, a write or deferred close
 * error; also one that stopped the recording earlier), with mocap_last_error() naming the file
 * and the cause: check it to know whether the capture on disk is complete. Afterwards the stats
 * are final (capture_bytes_written is what reached the file), polling returns what was left and
 * start() is refused. Calling it again returns the same status. One thread, and no other call on
 * this session may be in progress. */
MOCAP_API mocap_status mocap_session_stop(mocap_session *session);

/* mocap_session_stop (when it has not run) and free the session. NULL is accepted. After this
 * the handle is invalid. One thread, and no other call on this session may be in progress. */
MOCAP_API void mocap_session_close(mocap_session *session);

/* Copy the newest frame into *out, also after a pause of the consumer longer than the 1024
 * frames a live session keeps for drain (frames beyond those are dropped and counted, but the
 * newest is always kept for poll). A frame is handed out once: MOCAP_ERR_NO_DATA when no frame
 * is newer than the newest one poll or drain returned before, and drain skips frames older
 * than that. MOCAP_ERR_END_OF_STREAM once a replay is finished and drained. A replay
 * whose file stops reading (a removed drive) finishes there: END_OF_STREAM after the frames read
 * before the failure, and the stats' last_error names the file and the cause.
 * Consumer thread: one thread at a time polls/drains a session. */
MOCAP_API mocap_status mocap_session_poll_latest(mocap_session *session, mocap_frame *out);

/* Copy up to capacity frames produced since the previous drain, oldest first, into out;
 * *count receives how many. MOCAP_ERR_NO_DATA when there were none; END_OF_STREAM as above.
 * Consumer thread (same one as poll_latest). */
MOCAP_API mocap_status mocap_session_drain(mocap_session *session, mocap_frame *out,
                                           uint32_t capacity, uint32_t *count);

typedef enum mocap_connection_state {
    MOCAP_CONNECTION_CLOSED = 0,
    MOCAP_CONNECTION_CONNECTED = 1,
    MOCAP_CONNECTION_DISCONNECTED = 2, /* device lost; reconnecting when auto_reconnect */
    MOCAP_CONNECTION_ENDED = 3         /* replay finished (or its file stopped reading) */
} mocap_connection_state;

/* Counters and health of a running session. */
typedef struct mocap_session_stats {
    uint64_t bytes_received;
    uint64_t frames_decoded;      /* HiPNUC frames with a valid CRC */
    uint64_t crc_failures;
    uint64_t bytes_skipped;       /* garbage bytes discarded while resynchronising */
    uint64_t unknown_packets;     /* payloads with an unknown tag */
    uint64_t samples_decoded;     /* per-sensor samples (a 0x62 frame gives several) */
    uint64_t samples_rejected;    /* NaN/Inf, beyond any sensor's range, zero or non-unit
                                     quaternions, unknown nodes, older than one already taken */
    uint64_t frames_emitted;
    uint64_t frames_dropped;      /* output frames lost because the consumer was too slow */
    uint64_t bytes_dropped;       /* input bytes lost because processing was too slow */
    uint64_t reconnects;
    uint64_t capture_bytes_written;
    uint64_t replay_chunks_skipped; /* replay: damaged chunks of the capture passed over (what
                                       they held is missing from the frames) */
    int32_t connection_state;     /* mocap_connection_state */
    int32_t capture_error;        /* mocap_status of the capture writer (0 = fine) */
    uint32_t sensors_seen_mask;   /* bit i: sensor i (config order) produced a sample */
    int32_t replay_tail_damaged;  /* replay: 1 once the capture turned out to end in a damaged or
                                     incomplete chunk (a recording cut short), else 0 */
    char last_error[256];         /* last asynchronous error (device lost, disk full ...) */
} mocap_session_stats;

/* Any thread. */
MOCAP_API mocap_status mocap_session_get_stats(mocap_session *session, mocap_session_stats *out);

/* One counter of a session by key, as mocap_session_get_stats would report it. Keys are only ever
 * added (a minor version); a key this library does not know is MOCAP_ERR_UNSUPPORTED, naming it. */
typedef enum mocap_session_counter {
    MOCAP_SESSION_BYTES_RECEIVED = 0,
    MOCAP_SESSION_FRAMES_DECODED = 1,
    MOCAP_SESSION_CRC_FAILURES = 2,
    MOCAP_SESSION_BYTES_SKIPPED = 3,
    MOCAP_SESSION_UNKNOWN_PACKETS = 4,
    MOCAP_SESSION_SAMPLES_DECODED = 5,
    MOCAP_SESSION_SAMPLES_REJECTED = 6,
    MOCAP_SESSION_FRAMES_EMITTED = 7,
    MOCAP_SESSION_FRAMES_DROPPED = 8,
    MOCAP_SESSION_BYTES_DROPPED = 9,
    MOCAP_SESSION_RECONNECTS = 10,
    MOCAP_SESSION_CAPTURE_BYTES_WRITTEN = 11,
    MOCAP_SESSION_REPLAY_CHUNKS_SKIPPED = 12,
    MOCAP_SESSION_REPLAY_TAIL_DAMAGED = 13, /* 0 or 1 */
    MOCAP_SESSION_SENSORS_SEEN_MASK = 14,
    MOCAP_SESSION_COUNTER_COUNT = 15        /* the number of keys this header knows */
} mocap_session_counter;
/* Any thread. */
MOCAP_API mocap_status mocap_session_get_counter(mocap_session *session, int32_t counter,
                                                 uint64_t *out);

/* ------------------------------------------------------------------------------------------ */
/* Calibration                                                                                 */
/* ------------------------------------------------------------------------------------------ */
typedef enum mocap_calibration_step {
    /* All sensors lie still, X axis pointing the way the user will face, Z up. Gives each
     * sensor's world alignment (a yaw about world up). */
    MOCAP_CALIBRATION_HEADING = 0,
    /* Sensors strapped on, user stands still in a T-pose facing forward. Gives each sensor's
     * fixed rotation to its bone and its acceleration offset. */
    MOCAP_CALIBRATION_TPOSE = 1,
    /* Yaw-only re-alignment against drift: the user stands still facing forward, upright, arms
     * relaxed at the sides or out in a T-pose. Each calibrated sensor's world alignment is turned
     * about the vertical so its bone faces +Z again; mounting and offsets are kept (no T-pose). */
    MOCAP_CALIBRATION_HEADING_RESET = 2
} mocap_calibration_step;

typedef enum mocap_calibration_state {
    MOCAP_CALIBRATION_IDLE = 0,
    MOCAP_CALIBRATION_WAITING = 1,   /* scheduled, window not reached yet */
    MOCAP_CALIBRATION_COLLECTING = 2,
    MOCAP_CALIBRATION_ACCEPTED = 3,
    MOCAP_CALIBRATION_REFUSED = 4
} mocap_calibration_state;

/* Quality of one sensor over a calibration window. */
typedef struct mocap_sensor_quality {
    float gyro_rms_dps;        /* RMS angular rate over the window, deg/s (stillness) */
    float orientation_spread_deg; /* RMS angle of orientations about their mean */
    float accel_norm_error;    /* | |mean specific force| - g |, m/s^2 */
    float tilt_deg;            /* heading step: angle between sensor Z and world up */
    uint32_t samples;          /* frames with a fresh sample in the window */
    int32_t ok;                /* 1 if this sensor passed every check */
    int32_t segment;           /* mocap_segment */
    int32_t left_out;          /* 1: an optional sensor that sent nothing, left uncalibrated */
} mocap_sensor_quality;

typedef struct mocap_calibration_report {
    int32_t step;              /* mocap_calibration_step of the last request */
    int32_t state;             /* mocap_calibration_state */
    float progress;            /* 0..1 through the collection window */
    float seconds_remaining;
    uint32_t sensor_count;     /* the session's sensors, config order */
    mocap_sensor_quality sensors[MOCAP_MAX_SENSORS];
    char reason[256];          /* why it was refused, naming the sensor(s) */
} mocap_calibration_report;

/* The result of calibration: everything needed to turn raw sensor data into model-frame data.
 * Entry i belongs to the sensor on segments[i]; mocap_calibration_set applies each entry to the
 * session's sensor on the same segment, so a saved calibration survives a reordered config. */
typedef struct mocap_calibration {
    uint32_t struct_size;
    uint32_t sensor_count;
    uint32_t valid_mask;   /* bit i: heading and T-pose both done for entry i */
    uint32_t heading_mask; /* bit i: heading done for entry i */
    int32_t segments[MOCAP_MAX_SENSORS];
    /* Sensor world -> model frame (a yaw about world up, then Z-up to Y-up), row-major. */
    float world_to_model[MOCAP_MAX_SENSORS][9];
    /* Sensor frame -> bone frame (the mounting rotation), row-major. */
    float sensor_to_bone[MOCAP_MAX_SENSORS][9];
    /* Mean model-frame specific force during the T-pose, subtracted from every frame (gravity
     * plus bias), m/s^2. */
    float acceleration_offset[MOCAP_MAX_SENSORS][3];
} mocap_calibration;

/* Schedule a calibration step over the window [start_s, start_s + duration_s] of the session
 * clock (frame time). start_s < 0 means "from the next frame". Steps queue: one scheduled while
 * another is waiting or collecting starts after it, with its whole duration, at its own start
 * or when the one before finished, whichever is later (so a replay's heading and T-pose windows
 * can both be scheduled before mocap_session_start). Besides the step in progress, up to 8 steps
 * wait; more gives MOCAP_ERR_STATE. Calibration runs on the processing thread; poll the
 * reports. Any thread. */
MOCAP_API mocap_status mocap_calibration_schedule(mocap_session *session, int32_t step,
                                                  double start_s, float duration_s);

/* The latest step: the one waiting or collecting now, or else the last one that finished. A
 * step that starts replaces the previous result here, so with steps queued read each one's
 * result with mocap_calibration_get_step_report. Any thread. */
MOCAP_API mocap_status mocap_calibration_get_report(mocap_session *session,
                                                    mocap_calibration_report *out);
/* The latest request of one step (mocap_calibration_step): waiting, collecting or its result.
 * Any thread. */
MOCAP_API mocap_status mocap_calibration_get_step_report(mocap_session *session, int32_t step,
                                                         mocap_calibration_report *out);
/* Copy the calibration in use. Any thread. */
MOCAP_API mocap_status mocap_calibration_get(mocap_session *session, mocap_calibration *out);
/* Replace the calibration in use (e.g. loaded from a file): each of the session's sensors takes
 * the entry of its segment, and one without an entry becomes uncalibrated. A calibration that
 * shares no segment with the session is refused. Any thread. */
MOCAP_API mocap_status mocap_calibration_set(mocap_session *session, const mocap_calibration *cal);

/* Save/load a calibration as a small versioned text file. Any thread. */
MOCAP_API mocap_status mocap_calibration_save(const mocap_calibration *cal, const char *path);
MOCAP_API mocap_status mocap_calibration_load(const char *path, mocap_calibration *out);

/* ------------------------------------------------------------------------------------------ */
/* Pose model and solver (docs/model-contract.md)                                              */
/* ------------------------------------------------------------------------------------------ */
#define MOCAP_JOINT_COUNT 24
#define MOCAP_MAX_CHARACTERS 64

/* The Unity humanoid bone (a HumanBodyBones name: "Hips", "LeftShoulder" ...) that SMPL joint
 * `joint` (0..MOCAP_JOINT_COUNT-1, the contract order) drives, or NULL for the two hand end
 * points (left_hand, right_hand) and outside the range. The one SMPL -> humanoid map: the VMC
 * stream and the C# Humanoid driver both use it. Any thread; the text is static. */
MOCAP_API const char *mocap_humanoid_bone_name(int32_t joint);

typedef enum mocap_execution_provider {
    MOCAP_PROVIDER_CPU = 0,
    MOCAP_PROVIDER_CUDA = 1   /* needs a CUDA build of ONNX Runtime and a GPU; refused clearly otherwise */
} mocap_execution_provider;

typedef struct mocap_model_options {
    uint32_t struct_size;
    int32_t execution_provider;   /* mocap_execution_provider */
    int32_t intra_op_threads;     /* 1 (default); 0: ONNX Runtime's default, a thread per core
                                     whose idle threads spin */
    int32_t optimization_level;   /* 0 none, 1 basic, 2 extended, 3 all (default) */
    int32_t cuda_device;
    char onnxruntime_path[MOCAP_PATH_MAX]; /* "" = search (env MOCAP_ONNXRUNTIME_PATH, ...) */
} mocap_model_options;

/* What a model's metadata says (validated against the contract at load). */
typedef struct mocap_model_info {
    int32_t contract_version;     /* 1 (six fixed sensors), 2 (its own sensor set, with a mask) or
                                     3 (API 6.4: the network alone, the engine doing its geometry) */
    uint32_t sensor_count;        /* the model's sensors, in its input order */
    int32_t sensor_segments[MOCAP_MAX_SENSORS]; /* mocap_segment of input sensor k */
    uint32_t sensor_required_mask;/* bit k: the model needs sensor k; the others may be missing */
    float frame_rate;
    int32_t state_layers;
    int32_t state_size;
    int32_t joint_parents[MOCAP_JOINT_COUNT];
    float rest_offsets[MOCAP_JOINT_COUNT][3];       /* metres, model frame; [0] = pelvis height */
    char joint_names[MOCAP_JOINT_COUNT][32];
    char precision[8];                              /* "fp32" / "fp16" / "int8" (weights) */
    char model_name[128];
} mocap_model_info;

typedef struct mocap_model mocap_model;

/* Any thread. */
MOCAP_API mocap_status mocap_model_options_defaults(mocap_model_options *options);
/* Load and validate an .onnx file (a wrong model is refused with what differs; the process
 * stays usable). options may be NULL. One thread per model. */
MOCAP_API mocap_status mocap_model_open(const char *path, const mocap_model_options *options,
                                        mocap_model **out);
MOCAP_API mocap_status mocap_model_get_info(const mocap_model *model, mocap_model_info *out);
/* Not while a solver uses it. NULL accepted. */
MOCAP_API void mocap_model_close(mocap_model *model);

/* Performer heights the engine accepts, metres (a model's training height too). */
#define MOCAP_HEIGHT_MIN_M 1.0f
#define MOCAP_HEIGHT_MAX_M 2.5f

/* (API 6.1) How a model's root speed follows the performer's size, from its optional metadata
 * mocap.training_height (the standing height of the body it learned, metres) and
 * mocap.stride_exponent (e: a performer S = height / training_height times that size moves
 * about S^e times as fast as the model predicts; 1 would mean the model cannot tell sizes apart,
 * 0 that it reads size perfectly from the accelerations). MOCAP_ERR_UNSUPPORTED when the model
 * does not carry them (mocap_solver_set_character_height then refuses heights). Any thread. */
MOCAP_API mocap_status mocap_model_get_stride_scaling(const mocap_model *model,
                                                      float *training_height_m,
                                                      float *stride_exponent);

/* Solver: runs the model for several characters (each a session: device + calibration) on its
 * own thread, batched in one inference call per tick, and turns the outputs into poses with
 * root motion and contact-based drift correction. */
typedef struct mocap_solver_config {
    uint32_t struct_size;
    float contact_threshold;   /* foot_contact probability that counts as planted (0.5) */
    float floor_height;        /* metres, model frame (0) */
    int32_t drift_correction;  /* 1: planted feet curb root sliding, stand on the floor (default) */
    int32_t require_calibration; /* 1: only frames whose model-required sensors are calibrated
                                    are solved (default) */
    /* Output smoothing, a one-euro filter per joint rotation that follows each joint's turning
     * rate: the cut-off frequency is smoothing_min_cutoff_hz for a joint at rest and rises by
     * smoothing_beta Hz per rad/s of the joint's speed, so slow motion loses its jitter and fast
     * motion does not lag. smoothing_min_cutoff_hz = 0 turns it off (the model's raw output).
     * Defaults 2.0 Hz, 12.0. */
    float smoothing_min_cutoff_hz;
    float smoothing_beta;
} mocap_solver_config;

/* Pose flags. */
enum {
    MOCAP_POSE_CONTACT_LEFT = 1u << 0,
    MOCAP_POSE_CONTACT_RIGHT = 1u << 1,
    MOCAP_POSE_CORRECTED = 1u << 2,   /* drift correction moved the root this frame */
    MOCAP_POSE_INCOMPLETE = 1u << 3   /* some model sensor was held, silent or missing */
};

/* One solved pose of one character. Rotations are quaternions (w,x,y,z). */
typedef struct mocap_pose {
    uint64_t sequence;            /* per character, 0, 1, 2 ... */
    uint64_t frame_sequence;      /* the session frame it was solved from */
    double time_s;                /* that frame's time */
    uint32_t character;
    uint32_t flags;               /* MOCAP_POSE_* */
    float joint_rotations[MOCAP_JOINT_COUNT][4]; /* joint 0 global (model frame), others local */
    float joint_positions[MOCAP_JOINT_COUNT][3]; /* world, model frame, metres */
    float root_position[3];
    float root_velocity[3];       /* model output, m/s (times the height's stride gain) */
    float foot_contact[2];        /* probabilities, left/right */
    int64_t newest_receive_ns;    /* bytes that fed the input frame arrived (session clock) */
    int64_t frame_emitted_ns;     /* the input frame was assembled */
    int64_t pose_emitted_ns;      /* the pose was available */
} mocap_pose;

typedef struct mocap_solver mocap_solver;

MOCAP_API mocap_status mocap_solver_config_defaults(mocap_solver_config *config);
/* config may be NULL. The model must stay open while the solver lives. A character's session
 * must carry every sensor the model requires (by segment; refused naming the missing segment);
 * a model's optional sensor the session lacks is always fed as missing. A model with the mask
 * (contract 2, or 3 with masked features) gets 0 with zero inputs for a sensor it has nothing of
 * (not in the session, never sent, uncalibrated), else 1. A silent sensor gets a stand-in, the
 * same for every model: a shin or the head its bone in the model's previous pose, at rest; a
 * wrist its last sample turned about the vertical as far as the pelvis turned since; a wrist or
 * the head then moves over 4 s towards the bone's usual orientation relative to the pelvis'
 * heading; the pelvis (every model reads the body in its frame) its last sample turned about
 * the vertical as far as the shins turned since, at rest. A held pelvis or wrist sample (the
 * moments before a sensor counts as silent) is turned the same way. A sensor that comes back
 * is fed its readings turned by the stand-in's offset at its return, the offset fading out
 * over 0.15 s, so the bone does not snap round in one frame. */
MOCAP_API mocap_status mocap_solver_open(mocap_model *model, const mocap_solver_config *config,
                                         mocap_solver **out);
/* Before mocap_solver_start. The solver becomes the consumer of the session's frames (do not
 * poll/drain the session yourself afterwards); the session's output rate must equal the model's
 * frame rate. *character receives the index (0, 1, ...). */
MOCAP_API mocap_status mocap_solver_add_character(mocap_solver *solver, mocap_session *session,
                                                  int32_t *character);
/* Starts the inference thread (start the sessions yourself, before or after). */
MOCAP_API mocap_status mocap_solver_start(mocap_solver *solver);
/* Stops the thread and frees the solver (not the sessions or the model). NULL accepted. Close the
 * solver before its sessions: the thread reads them until it stops. */
MOCAP_API void mocap_solver_close(mocap_solver *solver);
/* Newest pose of a character, also after a pause of the consumer longer than the 1024 poses
 * kept for drain; MOCAP_ERR_NO_DATA when nothing is newer than what poll or drain returned
 * before (drain likewise skips poses older than that); MOCAP_ERR_END_OF_STREAM when the
 * character's replay is finished and all its poses were taken. One consumer thread. */
MOCAP_API mocap_status mocap_solver_poll_latest(mocap_solver *solver, int32_t character,
                                                mocap_pose *out);
MOCAP_API mocap_status mocap_solver_drain(mocap_solver *solver, int32_t character,
                                          mocap_pose *out, uint32_t capacity, uint32_t *count);
/* Clears a character's recurrent state and root motion (e.g. after a new calibration). Any
 * thread; takes effect before its next frame. */
MOCAP_API mocap_status mocap_solver_reset_character(mocap_solver *solver, int32_t character);
/* (API 6.1) The performer's standing height in metres (MOCAP_HEIGHT_MIN_M..MOCAP_HEIGHT_MAX_M),
 * or 0 for the model's own training height (the default). The pose keeps the model's skeleton;
 * the root's velocity is scaled by S^(e-1), S = height / training_height, e the model's stride
 * exponent (mocap_model_get_stride_scaling), so the root moves as far for the skeleton as the
 * performer did for their body and planted feet do not slide: a performer taller than the
 * training body is read by the model as taking longer strides than the skeleton can. A model
 * without stride scaling refuses a height with MOCAP_ERR_UNSUPPORTED (0 is always accepted).
 * Any thread; takes effect from the character's next frame. */
MOCAP_API mocap_status mocap_solver_set_character_height(mocap_solver *solver, int32_t character,
                                                         float height_m);
/* Largest delay mocap_solver_set_smoothing_delay takes, frames. */
#define MOCAP_SMOOTHING_DELAY_MAX 4
/* (API 6.2) Output smoothing that waits: with frames > 0 each character's pose of frame t is the
 * centred binomial average of its joint rotations over frames t - frames .. t + frames (frames =
 * 1: 1/4, 1/2, 1/4), emitted once frame t + frames is solved, stamped with frame t's sequence and
 * time; the one-euro filter (smoothing_min_cutoff_hz) is then not applied. Motion that is steady
 * over the window passes unchanged, so the noise goes without the lag a filter of the newest
 * frame has, for `frames` frame periods of latency (pose_emitted_ns - frame_emitted_ns shows
 * them): for recording and streaming, not for a VR avatar. The window's ends repeat the first
 * frame after a start or reset and the last frame when a session ends, so every frame still gets
 * its pose. 0 (the default) turns it off. Before mocap_solver_start; one thread. */
MOCAP_API mocap_status mocap_solver_set_smoothing_delay(mocap_solver *solver, int32_t frames);
/* Fastest slide mocap_solver_set_foot_pinning takes, m/s. */
#define MOCAP_FOOT_PIN_SLIDE_MAX 1.0f
/* (API 6.3) Foot pinning: with slide_m_s > 0, a foot whose contact probability reaches the
 * contact threshold is held where it touched down in the poses handed out, its leg bent to reach
 * it (hip and knee by two-bone inverse kinematics, the ankle keeping its global rotation). The
 * held point follows the predicted foot at up to slide_m_s and stays within 5 cm of it; after
 * lift-off the offset fades with a 0.1 s time constant (below 5 % in 0.3 s). Root motion,
 * contacts and the rest of the body are unchanged. 0 (the default) turns it off. Before
 * mocap_solver_start; one thread. */
MOCAP_API mocap_status mocap_solver_set_foot_pinning(mocap_solver *solver, float slide_m_s);
/* The tolerances mocap_solver_set_pose_limits takes besides 0, degrees. */
#define MOCAP_POSE_LIMITS_MIN_DEG 1.0f
#define MOCAP_POSE_LIMITS_MAX_DEG 90.0f
/* (API 6.5) Pose limits: with tolerance_deg > 0, a joint the model bends where no person's joint
 * goes is turned back before anything else reads the pose. Each joint's local rotation (the
 * root's global orientation excepted) is compared with the range of rotations that joint takes
 * in the training people's motion capture, built into the engine; one further than tolerance_deg
 * from all of them is turned along the shortest way until it is tolerance_deg away; the pose
 * handed out is guarded again after smoothing (the range is not convex, so an average of
 * guarded poses can leave it). A pose within the range passes unchanged. 25 keeps every joint
 * within the range `python3 -m training pose-range` judges broken poses by (30 deg). The SMPL-24 contract's joints and local frames;
 * the same range serves any model of that contract. 0 (the default) turns it off. Before
 * mocap_solver_start; one thread. */
MOCAP_API mocap_status mocap_solver_set_pose_limits(mocap_solver *solver, float tolerance_deg);
/* (API 6.6) Chest following, for a model that reads a chest sensor (MOCAP_SEGMENT_CHEST): with
 * share > 0 (up to 1), whenever the chest sensor has a sample of its own, the spine's joints are
 * turned so the chest bone moves `share` of the way from where the model put it to where the
 * sensor reports it, spread over the lower back as people bend it (two thirds of the turn at the
 * lowest joint, all of it at the next; the chest keeps its bend from there). The neck and collars
 * move with the chest; the head and the upper arms keep the orientation the model gave them. The
 * model leaves the chest about 7 deg from its sensor; 0.5, chosen on the training people, takes
 * validation people's joint positions through the engine from 5.23 to 4.64 cm
 * (`training/results/chest-follow/`). Applied to the model's output, before
 * pose limits and smoothing. No effect for a model without a chest sensor. 0 (the default) turns
 * it off. Before mocap_solver_start; one thread. */
MOCAP_API mocap_status mocap_solver_set_chest_follow(mocap_solver *solver, float share);

/* Counters and health of a solver. A frame whose inference fails (ONNX Runtime out of memory,
 * a model that cannot run these inputs) keeps the character's previous pose and state and is
 * counted in run_failures; the first and the latest failure are kept with their text. */
typedef struct mocap_solver_stats {
    uint64_t ticks;               /* inference calls (one per tick that had a frame) */
    uint64_t batched_calls;       /* calls with two or more characters */
    uint64_t max_batch;
    uint64_t frames_solved;       /* frames fed to the model */
    uint64_t frames_uncalibrated; /* skipped: not calibrated while require_calibration */
    uint64_t frames_nonfinite;    /* NaN/Inf inputs: not fed, previous pose held */
    uint64_t outputs_nonfinite;   /* NaN/Inf model outputs: state kept, previous pose held */
    uint64_t poses_dropped;       /* live poses lost because the consumer was too slow */
    uint64_t run_failures;        /* frames whose inference failed (previous pose held) */
    uint64_t solve_ns_total;      /* gather + inference + poses, summed over ticks */
    uint64_t solve_ns_max;
    uint64_t run_ns_total;        /* inside the inference call */
    int32_t last_run_status;      /* mocap_status of the latest failed inference (0 = none) */
    uint32_t reserved;
    char first_run_error[256];    /* the first failure's text (the model, ONNX Runtime's words) */
    char last_run_error[256];     /* the latest failure's text */
} mocap_solver_stats;

/* Totals over all characters (character -1) or one character's frame counters (ticks, batches,
 * timings and the error texts are solver-wide either way). Any thread. */
MOCAP_API mocap_status mocap_solver_get_stats(mocap_solver *solver, int32_t character,
                                              mocap_solver_stats *out);

/* One solver counter by key (character -1 for the totals), as mocap_solver_get_stats would report
 * it. Keys are only ever added; a key this library does not know is MOCAP_ERR_UNSUPPORTED. */
typedef enum mocap_solver_counter {
    MOCAP_SOLVER_TICKS = 0,
    MOCAP_SOLVER_BATCHED_CALLS = 1,
    MOCAP_SOLVER_MAX_BATCH = 2,
    MOCAP_SOLVER_FRAMES_SOLVED = 3,
    MOCAP_SOLVER_FRAMES_UNCALIBRATED = 4,
    MOCAP_SOLVER_FRAMES_NONFINITE = 5,
    MOCAP_SOLVER_OUTPUTS_NONFINITE = 6,
    MOCAP_SOLVER_POSES_DROPPED = 7,
    MOCAP_SOLVER_RUN_FAILURES = 8,
    MOCAP_SOLVER_SOLVE_NS_TOTAL = 9,
    MOCAP_SOLVER_SOLVE_NS_MAX = 10,
    MOCAP_SOLVER_RUN_NS_TOTAL = 11,
    MOCAP_SOLVER_COUNTER_COUNT = 12 /* the number of keys this header knows */
} mocap_solver_counter;
/* Any thread. */
MOCAP_API mocap_status mocap_solver_get_counter(mocap_solver *solver, int32_t character,
                                                int32_t counter, uint64_t *out);

/* ------------------------------------------------------------------------------------------ */
/* Streaming and export: VMC protocol (OSC over UDP) and BVH files                              */
/* ------------------------------------------------------------------------------------------ */
/* VMC sender: one handle per character and destination. Each sent pose is ONE OSC bundle:
 *   /VMC/Ext/OK i(1) [i(calibration_state) i(0)]   loaded (+ calibrated, normal mode)
 *   /VMC/Ext/T f(pose time_s)
 *   /VMC/Ext/Root/Pos s("root") f(px py pz qx qy qz qw)
 *   /VMC/Ext/Bone/Pos s(bone) f(px py pz qx qy qz qw)   for each of the 22 mapped joints
 * Bones are named by Unity's HumanBodyBones: pelvis Hips, spine1 Spine, spine2 Chest, spine3
 * UpperChest, neck Neck, head Head, left/right_collar Left/RightShoulder, _shoulder UpperArm,
 * _elbow LowerArm, _wrist Hand, _hip UpperLeg, _knee LowerLeg, _ankle Foot, _foot Toes (the SMPL
 * left/right_hand joints have no bone). Coordinates are Unity's (left-handed, Y up, metres): the
 * model frame mirrored on X, position (x,y,z) -> (-x,y,z), quaternion (w,x,y,z) -> Unity
 * (x,-y,-z,w), sent in VMC's qx qy qz qw order.
 * Bone/Pos carries LOCAL transforms: each bone's rest offset from its parent (Unity coords) and
 * its local rotation. The avatar root ("root", the parent of Hips) stands on the floor under the
 * pelvis: Root/Pos = (pelvis world position - pelvis rest offset, identity rotation) and Hips =
 * (pelvis rest offset (0, pelvis height, 0), global pelvis rotation), so Root * Hips is exactly
 * the pelvis world pose; a receiver that ignores Root still gets the full body orientation, and
 * one that applies Root (root synchronisation) also gets the locomotion - no rotation is applied
 * twice. */
typedef struct mocap_vmc_options {
    uint32_t struct_size;
    float max_rate_hz;          /* at most this many bundles per second of pose time (default 60;
                                   <= 0: every pose). SlimeVR caps near 200 */
    int32_t allow_remote;       /* 0 (default): only loopback destinations; 1: any address */
    int32_t calibration_state;  /* sent in /VMC/Ext/OK: 3 (default) = calibrated; -1: send only
                                   /VMC/Ext/OK 1 */
} mocap_vmc_options;

typedef struct mocap_vmc_stats {
    uint64_t poses;             /* mocap_vmc_send_pose calls with a valid pose */
    uint64_t bundles_sent;
    uint64_t skipped_rate;      /* poses skipped by max_rate_hz */
    uint64_t send_failures;     /* datagrams the OS refused */
    uint64_t bytes_sent;
    uint32_t bones_per_bundle;  /* Bone/Pos messages in the last bundle */
    uint32_t last_bundle_size;  /* bytes */
} mocap_vmc_stats;

typedef struct mocap_vmc mocap_vmc;

/* Any thread. */
MOCAP_API mocap_status mocap_vmc_options_defaults(mocap_vmc_options *options);
/* destination: "host:port", "[v6]:port", "host", or NULL/"" = "127.0.0.1:39539". Resolved once.
 * A non-loopback destination is refused (MOCAP_ERR_PERMISSION) unless options->allow_remote;
 * a bad one fails naming it. Nothing listens: the socket only sends, and for a loopback
 * destination it is bound to loopback. options may be NULL. One thread per handle. */
MOCAP_API mocap_status mocap_vmc_open(const char *destination, const mocap_vmc_options *options,
                                      mocap_vmc **out);
/* Sends one pose as one bundle (no allocation). MOCAP_ERR_NO_DATA when the rate cap skipped it
 * (not a failure); MOCAP_ERR_IO when the OS refused the datagram. info is the model's
 * (joint names, parents, rest offsets); joints are found by their SMPL names. */
MOCAP_API mocap_status mocap_vmc_send_pose(mocap_vmc *vmc, const mocap_model_info *info,
                                           const mocap_pose *pose);
MOCAP_API mocap_status mocap_vmc_get_stats(const mocap_vmc *vmc, mocap_vmc_stats *out);
/* NULL accepted. */
MOCAP_API void mocap_vmc_close(mocap_vmc *vmc);

/* BVH writer of solved poses (the same writer as `mocapctl replay --out`): SMPL-24 skeleton from
 * the model info, metres, model frame, Euler angles continuous between frames; streaming and
 * crash-safe (the frame count in the header is rewritten at every flush). */
typedef enum mocap_bvh_rotation_order {
    MOCAP_BVH_ZXY = 0,  /* "Zrotation Xrotation Yrotation" (default) */
    MOCAP_BVH_XYZ = 1
} mocap_bvh_rotation_order;

typedef struct mocap_bvh_options {
    uint32_t struct_size;
    int32_t rotation_order;  /* mocap_bvh_rotation_order */
    float frame_rate;        /* Frame Time = 1 / frame_rate; 0 (default): the model's frame rate */
    uint32_t flush_every;    /* frames between flushes + header updates (default 1) */
} mocap_bvh_options;

typedef struct mocap_bvh_writer mocap_bvh_writer;

/* Any thread. */
MOCAP_API mocap_status mocap_bvh_options_defaults(mocap_bvh_options *options);
/* Creates (truncates) path and writes the header. options may be NULL. One thread per writer. */
MOCAP_API mocap_status mocap_bvh_open(const char *path, const mocap_model_info *info,
                                      const mocap_bvh_options *options, mocap_bvh_writer **out);
/* Appends pose->root_position and pose->joint_rotations as one frame. */
MOCAP_API mocap_status mocap_bvh_append(mocap_bvh_writer *writer, const mocap_pose *pose);
MOCAP_API uint64_t mocap_bvh_frames(const mocap_bvh_writer *writer);
/* Flushes, writes the final frame count and closes; returns the first write error. NULL ok. */
MOCAP_API mocap_status mocap_bvh_close(mocap_bvh_writer *writer);

/* ------------------------------------------------------------------------------------------ */
/* Layout description, so bindings in other languages can verify their struct mirrors.          */
/* ------------------------------------------------------------------------------------------ */
typedef struct mocap_field_layout {
    const char *struct_name;
    const char *field_name;
    uint32_t offset;
    uint32_t size;
} mocap_field_layout;

/* Returns a static table of every public struct field plus one row per struct with
 * field_name "" giving sizeof. *count receives its length. Any thread. */
MOCAP_API const mocap_field_layout *mocap_struct_layout(uint32_t *count);

#ifdef __cplusplus
}
#endif
#endif /* MOCAP_IMU_H */
