/* A solver's counters by key: the way counters grow without changing mocap_solver_stats. */
#include "error.h"
#include "mocap_imu.h"

mocap_status mocap_solver_get_counter(mocap_solver *solver, int32_t character, int32_t counter,
                                      uint64_t *out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "out is NULL");
    if (counter < 0 || counter >= MOCAP_SOLVER_COUNTER_COUNT)
        return mocap_fail(MOCAP_ERR_UNSUPPORTED, "solver counter %d is not known to this library (API %d.%d)",
                          (int)counter, MOCAP_API_VERSION, MOCAP_API_VERSION_MINOR);
    mocap_solver_stats stats;
    mocap_status st = mocap_solver_get_stats(solver, character, &stats);
    if (st != MOCAP_OK) return st;
    switch ((mocap_solver_counter)counter) {
    case MOCAP_SOLVER_TICKS: *out = stats.ticks; break;
    case MOCAP_SOLVER_BATCHED_CALLS: *out = stats.batched_calls; break;
    case MOCAP_SOLVER_MAX_BATCH: *out = stats.max_batch; break;
    case MOCAP_SOLVER_FRAMES_SOLVED: *out = stats.frames_solved; break;
    case MOCAP_SOLVER_FRAMES_UNCALIBRATED: *out = stats.frames_uncalibrated; break;
    case MOCAP_SOLVER_FRAMES_NONFINITE: *out = stats.frames_nonfinite; break;
    case MOCAP_SOLVER_OUTPUTS_NONFINITE: *out = stats.outputs_nonfinite; break;
    case MOCAP_SOLVER_POSES_DROPPED: *out = stats.poses_dropped; break;
    case MOCAP_SOLVER_RUN_FAILURES: *out = stats.run_failures; break;
    case MOCAP_SOLVER_SOLVE_NS_TOTAL: *out = stats.solve_ns_total; break;
    case MOCAP_SOLVER_SOLVE_NS_MAX: *out = stats.solve_ns_max; break;
    case MOCAP_SOLVER_RUN_NS_TOTAL: *out = stats.run_ns_total; break;
    case MOCAP_SOLVER_COUNTER_COUNT: break; /* refused above */
    }
    return MOCAP_OK;
}
