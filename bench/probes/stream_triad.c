// A STREAM-style triad over 3 x 320 MB: the memory bandwidth one process gets (run one copy, then two at once).
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
int main(void) {
  const long n = 40000000L; /* 3 x 320 MB */
  double *a = malloc(n * 8), *b = malloc(n * 8), *c = malloc(n * 8);
  for (long i = 0; i < n; ++i) { a[i] = 1; b[i] = 2; c[i] = 0; }
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  for (int r = 0; r < 10; ++r)
    for (long i = 0; i < n; ++i) c[i] = a[i] + 1.5 * b[i];
  clock_gettime(CLOCK_MONOTONIC, &t1);
  double s = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
  printf("triad %.1f GB/s (%g)\n", 10 * 3 * 8.0 * n / s / 1e9, c[n / 2]);
  return 0;
}
