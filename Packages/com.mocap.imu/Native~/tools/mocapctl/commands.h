/* mocapctl's commands, one translation unit each (cmd_*.c), dispatched by main.c's table. Each
 * gets the arguments after its name (after "bench decode" for the decoder's benchmark), already
 * checked against its options (options.h), and returns the process's exit status: 0 done, 1
 * failed (the cause printed), 2 usage error. */
#ifndef MOCAPCTL_COMMANDS_H
#define MOCAPCTL_COMMANDS_H

int cmd_synth(int argc, char **argv);
int cmd_replay(int argc, char **argv);      /* hands over to cmd_replay_pose with the model */
int cmd_replay_pose(int argc, char **argv); /* replay CAPTURE through the pose model */
int cmd_live(int argc, char **argv);
int cmd_record(int argc, char **argv);
int cmd_stream(int argc, char **argv);
int cmd_bench_decode(int argc, char **argv);
int cmd_bench(int argc, char **argv); /* argv[0]: pipeline, latency, scaling, tip or all */
int cmd_infer(int argc, char **argv);
int cmd_model_info(int argc, char **argv);
int cmd_version(int argc, char **argv);

/* The usage of `command` (main.c's table name) on stderr; returns 2, the usage error's status. */
int mocapctl_usage_error(const char *command);

#endif
