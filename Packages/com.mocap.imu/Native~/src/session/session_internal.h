/* Internal accessors of a session for other engine modules (the pose solver). */
#ifndef MOCAP_SESSION_INTERNAL_H
#define MOCAP_SESSION_INTERNAL_H

#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The configuration the session was opened with (never changes afterwards). */
const mocap_session_config *session_config(const mocap_session *session);

#ifdef __cplusplus
}
#endif
#endif
