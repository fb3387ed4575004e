// Pure arithmetic, no memory traffic: eight chains of dependent scalar multiply-adds, bound by their latency
// (about 6 cycles an iteration), not by the floating-point pipes. Two copies running as fast as one alone show
// that the second vCPU gets its own cycles, but not that it is another core: SMT siblings would leave each
// other idle pipes. fp_ports.c, which fills the pipes, tells cores from siblings. Quoted in the README.
#include <stdio.h>
#include <time.h>
int main(void) {
  struct timespec a, b;
  clock_gettime(CLOCK_MONOTONIC, &a);
  double x0 = 1.0, x1 = 1.1, x2 = 1.2, x3 = 1.3, x4 = 1.4, x5 = 1.5, x6 = 1.6, x7 = 1.7;
  for (long i = 0; i < 1500000000L; ++i) {
    x0 = x0 * 0.9999999 + 1e-9; x1 = x1 * 0.9999999 + 1e-9; x2 = x2 * 0.9999999 + 1e-9; x3 = x3 * 0.9999999 + 1e-9;
    x4 = x4 * 0.9999999 + 1e-9; x5 = x5 * 0.9999999 + 1e-9; x6 = x6 * 0.9999999 + 1e-9; x7 = x7 * 0.9999999 + 1e-9;
  }
  clock_gettime(CLOCK_MONOTONIC, &b);
  printf("%.2f s (%g)\n", (b.tv_sec - a.tv_sec) + 1e-9 * (b.tv_nsec - a.tv_nsec), x0 + x1 + x2 + x3 + x4 + x5 + x6 + x7);
  return 0;
}
