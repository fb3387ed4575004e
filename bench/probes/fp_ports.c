// Arithmetic that saturates a core's floating-point pipes, no memory traffic: twelve independent chains of
// four-lane multiply-adds (more than the pipes can start per cycle, unlike fp_spin.c's eight scalar chains,
// which wait on latency). Two copies on two physical cores run as fast as one alone; on SMT siblings of one
// core, which share the pipes, each runs about half as fast.
//   gcc -O2 -mavx2 bench/probes/fp_ports.c -o /tmp/ports && /tmp/ports
//   taskset -c 0 /tmp/ports & taskset -c 1 /tmp/ports; wait
#include <stdio.h>
#include <time.h>
typedef double v4 __attribute__((vector_size(32)));
int main(void) {
  struct timespec a, b;
  v4 x[12];
  for (int k = 0; k < 12; ++k) x[k] = (v4){1.0 + k, 1.1 + k, 1.2 + k, 1.3 + k};
  const v4 m = {0.9999999, 0.9999999, 0.9999999, 0.9999999}, c = {1e-9, 1e-9, 1e-9, 1e-9};
  clock_gettime(CLOCK_MONOTONIC, &a);
  for (long i = 0; i < 1500000000L; ++i) {
#pragma GCC unroll 12
    for (int k = 0; k < 12; ++k) x[k] = x[k] * m + c;
  }
  clock_gettime(CLOCK_MONOTONIC, &b);
  v4 s = {0, 0, 0, 0};
  for (int k = 0; k < 12; ++k) s += x[k];
  const double t = (b.tv_sec - a.tv_sec) + 1e-9 * (b.tv_nsec - a.tv_nsec);
  printf("%.2f s, %.2f vector flops per ns (%g)\n", t, 1500000000.0 * 12 * 2 / t * 1e-9, s[0] + s[1] + s[2] + s[3]);
  return 0;
}
