/* mocapctl: the engine without Unity. main() finds the command in the table below, answers
 * --help with that command's usage, refuses options the command does not take, and runs it.
 * One translation unit per command (cmd_*.c); the options each takes are options.h. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#define WIN32_LEAN_AND_MEAN
#define NOMINMAX
#include <windows.h>
#include <shellapi.h>
#endif

#include "cli_args.h"
#include "commands.h"
#include "interrupt.h"
#include "options.h"
#include "sensor_set.h"

typedef struct mocapctl_command {
    const char *name;    /* one word, or two for "bench decode" */
    const char *options; /* cli_args.h's list of the options it takes */
    const char *summary; /* its line in the overview */
    const char *usage;   /* `mocapctl NAME --help` */
    int (*run)(int argc, char **argv);
} mocapctl_command;

static const mocapctl_command COMMANDS[] = {
    {"synth", MOCAPCTL_SYNTH_OPTIONS, "write a generated capture of a known motion (and its truth)",
     "usage: mocapctl synth --out CAPTURE [--truth CSV] [--motion walk|arms|squat|turn|mixed]\n"
     "                      [--seconds S] [--world nwu|enu] [--noise none|realistic] [--seed N]\n"
     "                      [--corrupt P] [--dropout P] [--trajectory FILE] [--sensors LIST]\n"
     "                      [--silence SEGMENT@START+LENGTH ...]\n"
     "A 0x62 capture of the sensor set (default: six nodes): a calibration prelude (heading 3 s,\n"
     "strap 2 s, T-pose 3 s), then the motion. The truth CSV has a column group per sensor.\n"
     "  --out CAPTURE        the capture to write\n"
     "  --truth CSV          the generator's truth: phase, bone orientations and accelerations\n"
     "  --motion NAME        a built-in motion (default mixed)\n"
     "  --trajectory FILE    the motion from a file instead (docs/synth-trajectory.md)\n"
     "  --seconds S          the motion's length (shortens it; it cannot lengthen it)\n"
     "  --world nwu|enu      the sensors' world frame (default nwu)\n"
     "  --noise none|realistic  sensor noise (default realistic)\n"
     "  --seed N             random seed (default 1)\n"
     "  --corrupt P          probability of a corrupted byte\n"
     "  --dropout P          probability of a node missing from a gateway frame\n"
     "  --silence SEG@S+L    the sensor on segment SEG sends nothing from S to S+L seconds of\n"
     "                       the motion (after the prelude); repeatable, up to 16\n"
     SENSOR_SET_HELP,
     cmd_synth},
    {"replay", MOCAPCTL_REPLAY_OPTIONS, "decode, calibrate and solve a capture; accuracy against a truth",
     "usage: mocapctl replay CAPTURE [--truth CSV] [--calibration FILE | --prelude H,S,T]\n"
     "                      [--save-calibration FILE] [--csv FRAMES.csv] [--realtime] [--rate HZ]\n"
     "                      [--sensors LIST]\n"
     "       mocapctl replay CAPTURE [--model M.onnx] [--out POSE.bvh] [--bvh-order zxy|xyz]\n"
     "                      [--json POSES.jsonl] [--pose-csv POSES.csv] [--truth CAPTURE.truth.csv]\n"
     "                      [--metrics-json ACCURACY.json] [--smoothing HZ[,BETA]|waitN] [--height M]\n"
     "                      [--foot-pin SPEED] [--pose-limits DEG] [--chest-follow SHARE]\n"
     "                      [--sensors LIST]\n"
     "The first form: decode -> filter -> calibrate, a summary per sensor and, with synth's truth,\n"
     "the bone orientation error. The second runs the pose model too (decode -> filter ->\n"
     "calibrate -> model -> drift correction): chosen by --model, --out, --json, --pose-csv or a\n"
     "pose truth (`python3 -m training synth-capture` writes CAPTURE.truth.csv).\n"
     "  --truth CSV          the truth to measure against (sensor or pose truth)\n"
     "  --calibration FILE   a saved calibration instead of the capture's prelude\n"
     "  --prelude H,S,T      the prelude's heading, strap and T-pose seconds (default 3,2,3)\n"
     "  --save-calibration FILE  the calibration made from the prelude\n"
     "  --csv FRAMES.csv     every sensor frame (without the model)\n"
     "  --realtime           at the capture's pace (default: as fast as possible)\n"
     "  --rate HZ            sensor frames per second (without the model; default 60)\n"
     "  --model M.onnx       the pose model (default: the shipped int8 model, or $MOCAP_MODEL)\n"
     "  --out POSE.bvh       BVH: SMPL-24 skeleton, metres, at the model's frame rate\n"
     "  --bvh-order zxy|xyz  the BVH's Euler order (default zxy)\n"
     "  --json POSES.jsonl   one JSON object per pose\n"
     "  --pose-csv POSES.csv one CSV line per pose\n"
     "  --metrics-json ACCURACY.json  with a pose truth: the accuracy figures as JSON\n"
     "  --smoothing HZ[,BETA]  the output filter's cut-off at rest and its rise per rad/s\n"
     "                       (default 2,12; 0 = the model's raw output); waitN: the centred\n"
     "                       average of N frames either side, each pose N frames later\n"
     HEIGHT_HELP
     FOOT_PIN_HELP
     POSE_LIMITS_HELP
     CHEST_FOLLOW_HELP
     SENSOR_SET_HELP
     "                       with the model, the sensors it does not require are optional\n",
     cmd_replay},
    {"live", MOCAPCTL_LIVE_OPTIONS, "guided calibration on real sensors, then live status or poses",
     "usage: mocapctl live --port DEV [--baud B] [--record CAPTURE] [--seconds S] [--model M | --pose]\n"
     "                    [--smoothing HZ[,BETA]|waitN] [--height M] [--foot-pin SPEED]\n"
     "                    [--pose-limits DEG] [--chest-follow SHARE] [--sensors LIST]\n"
     "The heading and T-pose steps with a countdown, then a status line until Ctrl-C.\n"
     "  --port DEV           the receiver's serial port\n"
     "  --baud B             its baud rate\n"
     "  --record CAPTURE     keep every byte in a capture file\n"
     "  --seconds S          stop after S seconds\n"
     "  --model M, --pose    run the pose model (--pose: the shipped one) and show pose status\n"
     "  --smoothing HZ[,BETA]  the output filter (default 2,12; 0 = off); waitN: the centred\n"
     "                       average of N frames either side, each pose N frames later\n"
     HEIGHT_HELP
     FOOT_PIN_HELP
     POSE_LIMITS_HELP
     CHEST_FOLLOW_HELP
     SENSOR_SET_HELP
     "                       with the model, the sensors it does not require are optional\n",
     cmd_live},
    {"record", MOCAPCTL_RECORD_OPTIONS, "record a live port's bytes into a capture",
     "usage: mocapctl record --port DEV --out CAPTURE [--baud B] [--seconds S] [--sensors LIST]\n"
     "  --port DEV           the receiver's serial port\n"
     "  --out CAPTURE        the capture to write\n"
     "  --baud B             its baud rate\n"
     "  --seconds S          stop after S seconds (default: at Ctrl-C)\n"
     SENSOR_SET_HELP,
     cmd_record},
    {"stream", MOCAPCTL_STREAM_OPTIONS, "solved poses to VMC receivers (OSC over UDP)",
     "usage: mocapctl stream --vmc HOST:PORT [--vmc ...] (--replay CAPTURE [--replay ...]\n"
     "                      [--speed X | --fast] [--prelude H,S,T] | --port DEV [--baud B]) [--model M]\n"
     "                      [--rate HZ] [--seconds S] [--allow-remote] [--smoothing HZ[,BETA]|waitN]\n"
     "                      [--height M] [--foot-pin SPEED] [--pose-limits DEG]\n"
     "                      [--chest-follow SHARE] [--sensors LIST]\n"
     "Character i (the i-th --replay, or the one --port) goes to the i-th --vmc.\n"
     "  --vmc HOST:PORT      a receiver (VSeeFace, EVMC4U, VMC4B listen on 39539)\n"
     "  --replay CAPTURE     a character from a capture\n"
     "  --realtime           at the capture's pace, one pose every 1/rate s (the default)\n"
     "  --speed X            at X times the capture's pace\n"
     "  --fast               as fast as the model solves (no pacing)\n"
     "  --prelude H,S,T      the prelude's heading, strap and T-pose seconds (default 3,2,3)\n"
     "  --port DEV, --baud B a character from a live port, after the guided calibration\n"
     "  --model M            the pose model (default: the shipped one)\n"
     "  --rate HZ            at most this many bundles per second (default 60)\n"
     "  --seconds S          stop after S seconds\n"
     "  --allow-remote       allow destinations that are not this machine\n"
     "  --smoothing HZ[,BETA]  the output filter (default 2,12; 0 = off); waitN: the centred\n"
     "                       average of N frames either side, each pose N frames later\n"
     HEIGHT_HELP
     FOOT_PIN_HELP
     POSE_LIMITS_HELP
     CHEST_FOLLOW_HELP
     SENSOR_SET_HELP
     "                       the sensors the model does not require are optional\n",
     cmd_stream},
    {"bench decode", MOCAPCTL_BENCH_DECODE_OPTIONS, "the decoder's throughput on one core",
     "usage: mocapctl bench decode [--seconds S]\n"
     "Decodes a generated 6-node 0x62 stream for about S seconds (default 3); prints MB/s.\n",
     cmd_bench_decode},
    {"bench", MOCAPCTL_BENCH_OPTIONS, "figures of the engine with the pose model",
     "usage: mocapctl bench pipeline|latency|scaling|tip|all [--model M] [--seconds S] [--threads N]\n"
     "                      [--tip-model F] [--max-characters N] [--latency-seconds S]\n"
     "                      [--tip-seconds S] [--sensors LIST]\n"
     "Figures, not tests: pipeline (frames/s of one character, peak RSS), latency (byte -> pose on\n"
     "a pseudo-terminal), scaling (characters through one solver), tip (a TIP-shaped network re-run\n"
     "over a window per frame against our model). The decoder's benchmark: bench decode --help.\n"
     "  --model M            the pose model (default: the shipped one)\n"
     "  --seconds S          motion seconds of the generated capture (default 30)\n"
     "  --latency-seconds S  the live session's length for latency (default 10)\n"
     "  --tip-seconds S      seconds per model in tip (default 3)\n"
     "  --threads N          ONNX Runtime threads in tip (default 1)\n"
     "  --max-characters N   scaling stops above N (default 32)\n"
     "  --tip-model F        the TIP-shaped model (default: $MOCAP_TIP_MODEL or made by training)\n"
     SENSOR_SET_HELP
     "                       of the generated capture and the sessions; the sensors the model\n"
     "                       does not require are optional\n",
     cmd_bench},
    {"infer", MOCAPCTL_INFER_OPTIONS, "run a pose model on tensor files (for training's checks)",
     "usage: mocapctl infer --model M.onnx --input IN --output OUT [--frames T | --stream] [--batch B]\n"
     "                     [--threads N] [--opt 0-3] [--provider cpu|cuda] [--repeat R]\n"
     "                     [--ort LIBONNXRUNTIME]\n"
     "IN and OUT are tensor bundles (the format: tools/mocapctl/cmd_infer.c); prints the timing.\n"
     "  --frames T, --stream T frames per call (--stream: 1, as the engine runs it; default all)\n"
     "  --batch B            the characters the input must hold\n"
     "  --threads N          ONNX Runtime intra-op threads\n"
     "  --opt 0-3            graph optimisation level (default 3)\n"
     "  --provider cpu|cuda  execution provider (default cpu)\n"
     "  --repeat R           run the whole sequence R times (timing)\n"
     "  --ort LIBONNXRUNTIME the ONNX Runtime library to load\n",
     cmd_infer},
    {"model-info", MOCAPCTL_MODEL_INFO_OPTIONS, "what a pose model's metadata says",
     "usage: mocapctl model-info M.onnx [--ort LIBONNXRUNTIME]\n"
     "  --ort LIBONNXRUNTIME the ONNX Runtime library to load\n",
     cmd_model_info},
    {"version", MOCAPCTL_VERSION_OPTIONS, "the engine's version and API version",
     "usage: mocapctl version\n", cmd_version},
};

#define COMMAND_COUNT (sizeof COMMANDS / sizeof COMMANDS[0])

/* The command named by the first words of argv (the longest name first: "bench decode" before
 * "bench"); *words: how many words the name took. NULL when none. */
static const mocapctl_command *find_command(int argc, char **argv, int *words)
{
    for (size_t i = 0; i < COMMAND_COUNT; ++i) {
        const char *name = COMMANDS[i].name;
        const char *space = strchr(name, ' ');
        if (!space) {
            if (argc >= 1 && strcmp(argv[0], name) == 0) {
                *words = 1;
                return &COMMANDS[i];
            }
        } else if (argc >= 2 && strncmp(argv[0], name, (size_t)(space - name)) == 0 &&
                   argv[0][space - name] == '\0' && strcmp(argv[1], space + 1) == 0) {
            *words = 2;
            return &COMMANDS[i];
        }
    }
    return NULL;
}

static const mocapctl_command *command_named(const char *name)
{
    for (size_t i = 0; i < COMMAND_COUNT; ++i)
        if (strcmp(COMMANDS[i].name, name) == 0) return &COMMANDS[i];
    return NULL;
}

int mocapctl_usage_error(const char *command)
{
    const mocapctl_command *c = command_named(command);
    if (c) fputs(c->usage, stderr);
    return 2;
}

static void print_overview(FILE *to)
{
    fputs("mocapctl: the motion-capture engine without Unity\n"
          "usage: mocapctl COMMAND [ARGUMENTS]\n"
          "       mocapctl COMMAND --help    the command's usage and options\n"
          "       mocapctl help [COMMAND]    this overview, or the command's usage\n"
          "commands:\n",
          to);
    for (size_t i = 0; i < COMMAND_COUNT; ++i)
        fprintf(to, "  %-14s %s\n", COMMANDS[i].name, COMMANDS[i].summary);
}

static int unknown_command(const char *name)
{
    fprintf(stderr, "mocapctl: unknown command '%s' (mocapctl help lists them)\n", name);
    return 2;
}

static int is_help(const char *arg)
{
    return strcmp(arg, "help") == 0 || strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0;
}

#if defined(_WIN32)
/* The command line as UTF-8, the encoding of the engine's paths: main's argv is in the ANSI code
 * page, where a file name outside it (say Japanese on a Western system) arrives as '?'. The
 * strings live until the process exits. NULL when Windows cannot give the wide command line. */
static char **utf8_arguments(int *argc)
{
    int n = 0;
    wchar_t **wide = CommandLineToArgvW(GetCommandLineW(), &n);
    if (!wide) return NULL;
    char **out = calloc((size_t)n + 1, sizeof *out);
    for (int i = 0; out && i < n; ++i) {
        int bytes = WideCharToMultiByte(CP_UTF8, 0, wide[i], -1, NULL, 0, NULL, NULL);
        if (bytes <= 0 || !(out[i] = malloc((size_t)bytes))) { out = NULL; break; }
        WideCharToMultiByte(CP_UTF8, 0, wide[i], -1, out[i], bytes, NULL, NULL);
    }
    LocalFree(wide);
    if (out) *argc = n;
    return out;
}
#endif

int main(int argc, char **argv)
{
#if defined(_WIN32)
    {
        char **utf8 = utf8_arguments(&argc);
        if (!utf8) {
            fprintf(stderr, "mocapctl: could not read the command line as Unicode\n");
            return 2;
        }
        argv = utf8;
        /* Paths and names print as UTF-8; a console shows them right in this code page. */
        SetConsoleOutputCP(CP_UTF8);
    }
#endif
    if (argc < 2) {
        print_overview(stderr);
        return 2;
    }
    mocapctl_catch_interrupt();
    int words = 0;
    if (is_help(argv[1])) {
        if (argc == 2) {
            print_overview(stdout);
            return 0;
        }
        const mocapctl_command *topic = find_command(argc - 2, argv + 2, &words);
        if (!topic) return unknown_command(argv[2]);
        fputs(topic->usage, stdout);
        return 0;
    }
    const mocapctl_command *c = find_command(argc - 1, argv + 1, &words);
    if (!c) return unknown_command(argv[1]);
    const int command_argc = argc - 1 - words;
    char **command_argv = argv + 1 + words;
    /* bench's benchmark name is a plain word: both checks pass over it. */
    if (cli_asks_for_help(command_argc, command_argv, c->options)) {
        fputs(c->usage, stdout);
        return 0;
    }
    cli_refuse_unknown(c->name, command_argc, command_argv, c->options);
    return c->run(command_argc, command_argv);
}
