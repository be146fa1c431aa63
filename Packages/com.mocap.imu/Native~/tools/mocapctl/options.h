/* The options each mocapctl command takes, as cli_args.h lists them ("--name=" takes a value,
 * "--name" is a flag): anything else that starts with "--" is refused before the command runs.
 * In a header of their own so that the test of the help texts can check that every option
 * accepted here is one the command's help shows, and that its help shows no other. */
#ifndef MOCAPCTL_OPTIONS_H
#define MOCAPCTL_OPTIONS_H

#define MOCAPCTL_SYNTH_OPTIONS                                                                    \
    "--out= --truth= --motion= --seconds= --world= --noise= --seed= --corrupt= --dropout= "      \
    "--trajectory= --sensors= --silence="
#define MOCAPCTL_REPLAY_OPTIONS                                                                   \
    "--truth= --calibration= --prelude= --save-calibration= --csv= --realtime --rate= "         \
    "--model= --out= --bvh-order= --json= --pose-csv= --metrics-json= --smoothing= --height= "  \
    "--foot-pin= --pose-limits= --chest-follow= --sensors="
#define MOCAPCTL_LIVE_OPTIONS                                                                     \
    "--port= --baud= --record= --seconds= --model= --pose --smoothing= --height= --foot-pin= "    \
    "--pose-limits= --chest-follow= --sensors="
#define MOCAPCTL_RECORD_OPTIONS "--port= --out= --baud= --seconds= --sensors="
#define MOCAPCTL_STREAM_OPTIONS                                                                   \
    "--vmc= --replay= --realtime --fast --speed= --prelude= --port= --baud= --model= --rate= "         \
    "--seconds= --allow-remote --smoothing= --height= --foot-pin= --pose-limits= --chest-follow= "\
    "--sensors="
#define MOCAPCTL_BENCH_DECODE_OPTIONS "--seconds="
#define MOCAPCTL_BENCH_OPTIONS                                                                    \
    "--model= --seconds= --latency-seconds= --tip-seconds= --threads= --max-characters= "       \
    "--tip-model= --sensors="
#define MOCAPCTL_INFER_OPTIONS                                                                    \
    "--model= --input= --output= --frames= --stream --batch= --threads= --opt= --provider= "    \
    "--repeat= --ort="
#define MOCAPCTL_MODEL_INFO_OPTIONS "--ort="
#define MOCAPCTL_VERSION_OPTIONS ""

#endif
