/*
 * battery.h: the random parameter sets of the search battery, shared by
 * tests/core/test_search.c and bench/bench_search.c so that both run the
 * same sets: chi 0.05-0.9, eta 0.2-20 and ur/us 1.5-20 log-uniform, us
 * 0.02-0.3, V = 1, from a fixed xorshift generator.
 */
#ifndef SS_BATTERY_H
#define SS_BATTERY_H

#include <math.h>
#include <stdint.h>

typedef struct battery {
  uint64_t state;
} battery;

static inline void battery_init(battery *b) { b->state = 0x2545f4914f6cdd1du; }

static inline double battery_unif(battery *b, double lo, double hi) {
  b->state ^= b->state >> 12;
  b->state ^= b->state << 25;
  b->state ^= b->state >> 27;
  return lo + (hi - lo) * (double)((b->state * 2685821657736338717u) >> 11) *
                  0x1p-53;
}

/* The next set: chi, eta, us, ur, V. */
static inline void battery_next(battery *b, double p[5]) {
  p[0] = battery_unif(b, 0.05, 0.9);
  p[1] = exp(battery_unif(b, log(0.2), log(20)));
  p[2] = battery_unif(b, 0.02, 0.3);
  p[3] = p[2] * exp(battery_unif(b, log(1.5), log(20)));
  p[4] = 1;
}

#endif
