/* Failure and loss reports of mocapctl's commands (report.h). */
#include "report.h"

#include <stdio.h>
#include <string.h>

int report_failure(mocap_status status, const char *what)
{
    fprintf(stderr, "mocapctl: %s: %s (%s)\n", what, mocap_last_error(), mocap_status_name(status));
    return 1;
}

int report_path_too_long(const char *path, const char *what)
{
    if (strlen(path) < MOCAP_PATH_MAX) return 0;
    fprintf(stderr, "mocapctl: the %s path is %u bytes long; the engine takes at most %d: %s\n",
            what, (unsigned)strlen(path), MOCAP_PATH_MAX - 1, path);
    return 1;
}

int report_inference_failures(mocap_solver *solver)
{
    mocap_solver_stats st;
    if (!solver || mocap_solver_get_stats(solver, -1, &st) != MOCAP_OK || st.run_failures == 0)
        return 0;
    fprintf(stderr, "mocapctl: inference failed for %llu of %llu frames (%s; their poses repeat "
                    "the previous one)\n  first: %s\n",
            (unsigned long long)st.run_failures, (unsigned long long)st.frames_solved,
            mocap_status_name((mocap_status)st.last_run_status), st.first_run_error);
    if (strcmp(st.first_run_error, st.last_run_error) != 0)
        fprintf(stderr, "  latest: %s\n", st.last_run_error);
    return 1;
}

void report_dropped(mocap_session *session, mocap_solver *solver, int32_t character,
                    const char *what, const char *remedy)
{
    mocap_session_stats ss;
    mocap_solver_stats ps;
    unsigned long long bytes = 0, frames = 0, poses = 0;
    if (mocap_session_get_stats(session, &ss) == MOCAP_OK) {
        bytes = (unsigned long long)ss.bytes_dropped;
        frames = (unsigned long long)ss.frames_dropped;
    }
    if (solver && mocap_solver_get_stats(solver, character, &ps) == MOCAP_OK)
        poses = (unsigned long long)ps.poses_dropped;
    if (bytes == 0 && frames == 0 && poses == 0) return;
    fprintf(stderr, "mocapctl: warning: %s: processing fell behind and lost %llu frame(s), %llu "
                    "pose(s) and %llu input byte(s) on the way; %s\n",
            what, frames, poses, bytes, remedy);
}

void report_capture_damage(mocap_session *session, const char *capture)
{
    mocap_session_stats stats;
    if (mocap_session_get_stats(session, &stats) != MOCAP_OK) return;
    if (stats.replay_chunks_skipped > 0)
        fprintf(stderr, "mocapctl: warning: capture %s: %llu damaged chunk(s) were skipped; what they "
                        "held is missing from the results\n",
                capture, (unsigned long long)stats.replay_chunks_skipped);
    if (stats.replay_tail_damaged)
        fprintf(stderr, "mocapctl: warning: capture %s ends in a damaged or incomplete chunk (a "
                        "recording cut short?); its last records are missing from the results\n", capture);
}

int report_replay_ended_early(mocap_session *session)
{
    mocap_session_stats stats;
    if (mocap_session_get_stats(session, &stats) != MOCAP_OK || stats.last_error[0] == '\0') return 0;
    fprintf(stderr, "mocapctl: the replay stopped before the end of the capture: %s\n", stats.last_error);
    return 1;
}
