/* Command-line option reading for mocapctl (cli_args.h). */
#include "cli_args.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if !defined(_WIN32)
#include <sys/stat.h>
#endif

static void usage_exit(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("mocapctl: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    exit(2);
}

const char *cli_value(int argc, char **argv, const char *name)
{
    for (int i = 0; i < argc; ++i) {
        if (strcmp(argv[i], name) != 0) continue;
        if (i + 1 >= argc) usage_exit("%s needs a value", name);
        if (strncmp(argv[i + 1], "--", 2) == 0)
            usage_exit("%s needs a value, not the option %s", name, argv[i + 1]);
        return argv[i + 1];
    }
    return NULL;
}

int cli_values(int argc, char **argv, const char *name, const char **out, int cap)
{
    int n = 0;
    for (int i = 0; i + 1 < argc; ++i) {
        if (strcmp(argv[i], name) == 0) {
            if (n == cap) return -1;
            out[n++] = argv[++i];
        }
    }
    return n;
}

int cli_flag(int argc, char **argv, const char *name)
{
    for (int i = 0; i < argc; ++i)
        if (strcmp(argv[i], name) == 0) return 1;
    return 0;
}

double cli_number(int argc, char **argv, const char *name, double fallback, double lo, double hi)
{
    const char *text = cli_value(argc, argv, name);
    if (!text) return fallback;
    char *end = NULL;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end != '\0' || errno == ERANGE || !isfinite(v))
        usage_exit("%s wants a number, got '%s'", name, text);
    if (v < lo || v > hi) usage_exit("%s %s is outside %g..%g", name, text, lo, hi);
    return v;
}

long long cli_integer(int argc, char **argv, const char *name, long long fallback, long long lo,
                      long long hi)
{
    const char *text = cli_value(argc, argv, name);
    if (!text) return fallback;
    char *end = NULL;
    errno = 0;
    long long v = strtoll(text, &end, 10);
    if (end == text || *end != '\0' || errno == ERANGE)
        usage_exit("%s wants a whole number, got '%s'", name, text);
    if (v < lo || v > hi) usage_exit("%s %s is outside %lld..%lld", name, text, lo, hi);
    return v;
}

unsigned long long cli_u64(int argc, char **argv, const char *name, unsigned long long fallback)
{
    const char *text = cli_value(argc, argv, name);
    if (!text) return fallback;
    char *end = NULL;
    errno = 0;
    unsigned long long v = strtoull(text, &end, 10);
    if (end == text || *end != '\0' || errno == ERANGE || text[0] == '-')
        usage_exit("%s wants a whole number from 0 to 2^64-1, got '%s'", name, text);
    return v;
}

/* Where `name` (its first `length` bytes) is in `known`: 0 absent, 1 a flag, 2 takes a value. */
static int option_kind(const char *known, const char *name, size_t length)
{
    const char *p = known;
    while (*p) {
        while (*p == ' ') ++p;
        const char *end = p;
        while (*end && *end != ' ' && *end != '=') ++end;
        if ((size_t)(end - p) == length && length > 0 && strncmp(p, name, length) == 0)
            return *end == '=' ? 2 : 1;
        p = end;
        while (*p && *p != ' ') ++p;
    }
    return 0;
}

/* 1 when argv[i] is an option of `known` that takes a value and argv[i + 1] is that value
 * (whatever it says: a file may be called -h). */
static int value_follows(const char *known, int argc, char **argv, int i)
{
    return strncmp(argv[i], "--", 2) == 0 && option_kind(known, argv[i], strlen(argv[i])) == 2 &&
           i + 1 < argc && strncmp(argv[i + 1], "--", 2) != 0;
}

int cli_asks_for_help(int argc, char **argv, const char *known)
{
    for (int i = 0; i < argc; ++i) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) return 1;
        if (value_follows(known, argc, argv, i)) ++i;
    }
    return 0;
}

void cli_refuse_unknown(const char *command, int argc, char **argv, const char *known)
{
    for (int i = 0; i < argc; ++i) {
        const char *arg = argv[i];
        if (strncmp(arg, "--", 2) != 0) continue;
        if (value_follows(known, argc, argv, i)) {
            ++i;
            continue;
        }
        if (option_kind(known, arg, strlen(arg)) != 0) continue;
        const char *equals = strchr(arg, '=');
        if (equals && option_kind(known, arg, (size_t)(equals - arg)) == 2)
            usage_exit("%s: write '%.*s %s': a value follows its option after a space", command,
                       (int)(equals - arg), arg, equals + 1);
        usage_exit("%s has no option %s ('mocapctl %s --help' lists them)", command, arg, command);
    }
}

void cli_refuse_options(int argc, char **argv, const char *names, const char *why)
{
    for (int i = 0; i < argc; ++i)
        if (option_kind(names, argv[i], strlen(argv[i])) != 0) usage_exit("%s %s", argv[i], why);
}

/* Both paths name one existing file (the same device and inode: links and other spellings
 * included). Windows has no inode numbers in stat: there, only identical text counts. */
static int same_file(const char *a, const char *b)
{
    if (strcmp(a, b) == 0) return 1;
#if !defined(_WIN32)
    struct stat sa, sb;
    if (stat(a, &sa) != 0 || stat(b, &sb) != 0) return 0;
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
#else
    return 0;
#endif
}

void cli_refuse_overwriting(const char *input, const char *input_what, int argc, char **argv,
                            const char *const *outputs)
{
    for (int i = 0; outputs[i]; ++i) {
        const char *out = cli_value(argc, argv, outputs[i]);
        if (!out) continue;
        if (input && same_file(out, input))
            usage_exit("%s %s is the %s this command reads: writing it would destroy it", outputs[i],
                       out, input_what);
        for (int j = 0; j < i; ++j) {
            const char *other = cli_value(argc, argv, outputs[j]);
            if (other && same_file(out, other))
                usage_exit("%s and %s name the same file (%s)", outputs[j], outputs[i], out);
        }
    }
}

/* The value of option name as a number in lo..hi: *out = it, 0 when the option is absent; -1
 * (nothing printed, *out 0) when its text is not such a number. *text_out: the text, or NULL. */
static int option_in_range(int argc, char **argv, const char *name, double lo, double hi,
                           float *out, const char **text_out)
{
    *out = 0.0f;
    const char *text = *text_out = cli_value(argc, argv, name);
    if (!text) return 0;
    char *end = NULL;
    double v = strtod(text, &end);
    if (end == text || *end != '\0' || !(v >= lo && v <= hi)) return -1;
    *out = (float)v;
    return 0;
}

int cli_height(int argc, char **argv, float *out)
{
    const char *text;
    if (option_in_range(argc, argv, "--height", MOCAP_HEIGHT_MIN_M, MOCAP_HEIGHT_MAX_M, out, &text) == 0)
        return 0;
    fprintf(stderr, "mocapctl: --height wants the performer's standing height in metres, "
                    "%g to %g, got '%s'\n", (double)MOCAP_HEIGHT_MIN_M, (double)MOCAP_HEIGHT_MAX_M, text);
    return 2;
}

int cli_foot_pin(int argc, char **argv, float *out)
{
    const char *text;
    if (option_in_range(argc, argv, "--foot-pin", 0.0, MOCAP_FOOT_PIN_SLIDE_MAX, out, &text) == 0)
        return 0;
    fprintf(stderr, "mocapctl: --foot-pin wants the fastest a planted foot may slide, m/s, "
                    "0 to %g, got '%s'\n", (double)MOCAP_FOOT_PIN_SLIDE_MAX, text);
    return 2;
}

int cli_pose_limits(int argc, char **argv, float *out)
{
    const char *text;
    if (option_in_range(argc, argv, "--pose-limits", 0.0, MOCAP_POSE_LIMITS_MAX_DEG, out, &text) == 0 &&
        (*out == 0.0f || *out >= MOCAP_POSE_LIMITS_MIN_DEG))
        return 0;
    fprintf(stderr, "mocapctl: --pose-limits wants 0 (off) or a tolerance in degrees, %g to %g, "
                    "got '%s'\n", (double)MOCAP_POSE_LIMITS_MIN_DEG, (double)MOCAP_POSE_LIMITS_MAX_DEG, text);
    return 2;
}

int cli_chest_follow(int argc, char **argv, float *out)
{
    const char *text;
    if (option_in_range(argc, argv, "--chest-follow", 0.0, 1.0, out, &text) == 0) return 0;
    fprintf(stderr, "mocapctl: --chest-follow wants the share of the way the spine turns to the "
                    "chest sensor, 0 (off) to 1, got '%s'\n", text);
    return 2;
}

int height_supported(const mocap_model *model, float height_m)
{
    float training_height, exponent;
    if (height_m == 0.0f ||
        mocap_model_get_stride_scaling(model, &training_height, &exponent) == MOCAP_OK)
        return 0;
    fprintf(stderr, "mocapctl: --height %g: %s\n", (double)height_m, mocap_last_error());
    return 1;
}

int apply_height(mocap_solver *solver, int32_t character, float height_m)
{
    if (height_m == 0.0f) return 0;
    mocap_status s = mocap_solver_set_character_height(solver, character, height_m);
    if (s == MOCAP_OK) return 0;
    fprintf(stderr, "mocapctl: --height %g: %s\n", (double)height_m, mocap_last_error());
    return 1;
}

/* "waitN": N frames of smoothing that waits (1..MOCAP_SMOOTHING_DELAY_MAX); 0 for any other
 * form, -1 for "wait" with a bad N. */
static int32_t smoothing_wait_frames(const char *v)
{
    if (strncmp(v, "wait", 4) != 0) return 0;
    char *end = NULL;
    long n = strtol(v + 4, &end, 10);
    return (end == v + 4 || *end != '\0' || n < 1 || n > MOCAP_SMOOTHING_DELAY_MAX) ? -1 : (int32_t)n;
}

int32_t cli_smoothing_delay(int argc, char **argv)
{
    const char *smoothing = cli_value(argc, argv, "--smoothing");
    int32_t n = smoothing ? smoothing_wait_frames(smoothing) : 0;
    return n > 0 ? n : 0;
}

int cli_smoothing(int argc, char **argv, mocap_solver_config *out)
{
    mocap_solver_config_defaults(out);
    const char *smoothing = cli_value(argc, argv, "--smoothing");
    if (!smoothing) return 0;
    const int32_t wait = smoothing_wait_frames(smoothing);
    if (wait > 0) return 0;   /* the solver's delay (cli_smoothing_delay); no one-euro filter */
    if (wait < 0) {
        fprintf(stderr, "mocapctl: --smoothing waitN wants N from 1 to %d frames, got '%s'\n",
                MOCAP_SMOOTHING_DELAY_MAX, smoothing);
        return 2;
    }
    char *end = NULL;
    double hz = strtod(smoothing, &end), beta = out->smoothing_beta;
    int bad = end == smoothing;
    if (!bad && *end == ',') {
        const char *b = end + 1;
        beta = strtod(b, &end);
        bad = end == b;
    }
    if (bad || *end != '\0' || !(hz >= 0.0 && hz < 1e6) || !(beta >= 0.0 && beta < 1e6)) {
        fprintf(stderr, "mocapctl: --smoothing wants HZ or HZ,BETA with HZ >= 0 (0: off) and "
                        "BETA >= 0, or waitN, got '%s'\n", smoothing);
        return 2;
    }
    out->smoothing_min_cutoff_hz = (float)hz;
    out->smoothing_beta = (float)beta;
    return 0;
}
