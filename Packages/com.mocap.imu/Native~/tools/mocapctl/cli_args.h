/* Command-line options of mocapctl's commands. A mistake in the command line (an option without
 * its value, a number that is not one or is out of range) is a usage error: printed once as
 * "mocapctl: ...", exit status 2, before the command opens or writes anything. */
#ifndef MOCAPCTL_CLI_ARGS_H
#define MOCAPCTL_CLI_ARGS_H

#include "mocap_imu.h"

/* The value after `name`, or NULL when `name` is not given. `name` as the last argument, or
 * followed by another --option, is a usage error (the option would silently lose its value, or
 * take the next option's name as a file name). */
const char *cli_value(int argc, char **argv, const char *name);
int cli_flag(int argc, char **argv, const char *name);
/* Every value of a repeated option (--vmc A --vmc B), in order, into out[0..cap): their count,
 * or -1 when there are more than `cap`. */
int cli_values(int argc, char **argv, const char *name, const char **out, int cap);
/* A number option: `fallback` when absent; otherwise the whole value must be a finite number
 * within [lo, hi]. */
double cli_number(int argc, char **argv, const char *name, double fallback, double lo, double hi);
/* The same for a whole number. */
long long cli_integer(int argc, char **argv, const char *name, long long fallback, long long lo,
                      long long hi);
/* An unsigned 64-bit whole number (seeds). */
unsigned long long cli_u64(int argc, char **argv, const char *name, unsigned long long fallback);

/* Usage error for an argument that looks like an option (`--name`) but is not one of the
 * command's: `known` is a space-separated list in which "--name=" takes a value and "--name" is
 * a flag. A mistyped option would otherwise be ignored and the command would run with the
 * default it was meant to change. `command` names the command in the message. */
void cli_refuse_unknown(const char *command, int argc, char **argv, const char *known);
/* 1 when --help or -h stands where an option would (not as the value of one of `known`). */
int cli_asks_for_help(int argc, char **argv, const char *known);

/* Usage error when one of `names` (space-separated, as in `known` above) is given in a mode of
 * the command that does not use it: "NAME WHY" (e.g. "--speed applies to --replay only"). */
void cli_refuse_options(int argc, char **argv, const char *names, const char *why);

/* Usage error when an output option names the file `input` (an existing file read by the
 * command: a capture, a truth file), or two outputs name one file: opening the output for
 * writing would empty the input before it is read. `outputs` ends with NULL. */
void cli_refuse_overwriting(const char *input, const char *input_what, int argc, char **argv,
                            const char *const *outputs);

/* The solver options of the pose commands: defaults, then --smoothing HZ[,BETA] (the one-euro
 * output filter's cut-off at rest, Hz, and its rise per rad/s of joint speed; 0 = the model's
 * raw output) or --smoothing waitN (smoothing that waits N frames: cli_smoothing_delay). 0, or 2
 * (a usage error, printed). */
int cli_smoothing(int argc, char **argv, mocap_solver_config *out);
/* N of a valid --smoothing waitN (for mocap_solver_set_smoothing_delay), else 0. */
int32_t cli_smoothing_delay(int argc, char **argv);
/* --height M (the performer's standing height, metres): *out = M, or 0 when absent; 2 (and a
 * message) when M is not a number in MOCAP_HEIGHT_MIN_M..MOCAP_HEIGHT_MAX_M, else 0. */
int cli_height(int argc, char **argv, float *out);
/* --foot-pin SPEED (m/s, for mocap_solver_set_foot_pinning): *out = SPEED, 0 when absent; 2
 * (and a message) when SPEED is not a number in 0..MOCAP_FOOT_PIN_SLIDE_MAX, else 0. */
int cli_foot_pin(int argc, char **argv, float *out);
/* --pose-limits DEG (for mocap_solver_set_pose_limits): *out = DEG, 0 when absent; 2 (and a
 * message) when DEG is neither 0 nor a number in MOCAP_POSE_LIMITS_MIN_DEG..MAX_DEG, else 0. */
int cli_pose_limits(int argc, char **argv, float *out);
/* --chest-follow SHARE (for mocap_solver_set_chest_follow): *out = SHARE, 0 when absent; 2 (and
 * a message) when SHARE is not a number in 0..1, else 0. */
int cli_chest_follow(int argc, char **argv, float *out);
#define CHEST_FOLLOW_HELP                                                                        \
    "  --chest-follow SHARE turn the spine SHARE (0..1) of the way from the model's chest to the\n" \
    "                       chest sensor's (0.5 suits the seven-sensor model; default 0: off)\n"
#define POSE_LIMITS_HELP                                                                         \
    "  --pose-limits DEG    turn a joint the model bends where no person's joint goes back to\n" \
    "                       within DEG degrees of the range people's joints take (25 keeps\n"    \
    "                       poses out of what training's pose-range calls broken; default 0:\n"  \
    "                       off)\n"
#define FOOT_PIN_HELP                                                                            \
    "  --foot-pin SPEED     hold planted feet where they landed, bending the legs, letting them\n" \
    "                       slide at most SPEED m/s (0.06 keeps the motion capture's own foot\n"  \
    "                       motion; default 0: off)\n"
#define HEIGHT_HELP                                                                              \
    "  --height M           the performer's standing height, metres: the root moves for the\n"   \
    "                       model's skeleton as far as they did for their body (needs a model\n" \
    "                       with stride scaling; default: the model's training height)\n"
/* Applies a height from cli_height to a solver's character (nothing for 0); 0, or 1 with the
 * engine's reason (e.g. a model without stride scaling). */
int apply_height(mocap_solver *solver, int32_t character, float height_m);
/* 0 when the model can take the height (always for 0), else 1 with the engine's reason. */
int height_supported(const mocap_model *model, float height_m);

#endif
