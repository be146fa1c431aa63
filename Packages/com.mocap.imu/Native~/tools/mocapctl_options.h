/* mocapctl's option table, in a header of its own so that the test of the usage text can check
 * that every option accepted here is also one the help shows. */
#ifndef MOCAPCTL_OPTIONS_H
#define MOCAPCTL_OPTIONS_H

/* The options each command takes, as the usage text lists them ("--name=" takes a value):
 * anything else that starts with "--" is refused before the command runs. */
static const struct {
    const char *command;
    const char *options;
} mocapctl_command_options[] = {
    {"synth", "--out= --truth= --motion= --seconds= --world= --noise= --seed= --corrupt= "
              "--dropout= --trajectory="},
    {"replay", "--truth= --calibration= --prelude= --save-calibration= --csv= --realtime --rate= "
               "--model= --out= --bvh-order= --json= --pose-csv= --metrics-json= --smoothing="},
    {"live", "--port= --baud= --record= --seconds= --model= --pose --smoothing="},
    {"record", "--port= --out= --baud= --seconds="},
    {"stream", "--vmc= --replay= --realtime --speed= --prelude= --port= --baud= --model= --rate= "
               "--seconds= --allow-remote --smoothing="},
    {"bench decode", "--seconds="},
    {"bench", "--model= --seconds= --latency-seconds= --tip-seconds= --threads= "
              "--max-characters= --tip-model="},
    {"infer", "--model= --input= --output= --frames= --stream --batch= --threads= --opt= "
              "--provider= --repeat= --ort="},
    {"model-info", "--ort="},
    {"version", ""},
};

#endif
