/* Micro-benchmarks behind `mocapctl bench`. */
#ifndef MOCAPCTL_BENCH_H
#define MOCAPCTL_BENCH_H

#ifdef __cplusplus
extern "C" {
#endif

/* Decode a generated 6-node 0x62 stream (a few MB, fed in 4 KB chunks) repeatedly for about
 * `seconds` on the calling thread, verify that every frame came out, print the throughput to
 * stdout and store it in *mb_per_s (10^6 bytes per second; may be NULL). Returns 0 (MOCAP_OK),
 * or a mocap_status after printing the cause to stderr. */
int mocapctl_bench_decode(double seconds, double *mb_per_s);

#ifdef __cplusplus
}
#endif
#endif
