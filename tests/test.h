/*
 * test.h: a small assertion kit for the tests.  Every failing assertion
 * prints the expression, both values and file:line, and the test goes on, so
 * one run shows every failure; TEST_DONE() returns the exit status.
 */
#ifndef SS_TEST_H
#define SS_TEST_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* A test of several files (tests/http/fixture.h) defines
 * TEST_SHARED_COUNTERS before including this header, and one of its files
 * defines the two counters. */
#ifdef TEST_SHARED_COUNTERS
extern int test_failures_, test_checks_;
#else
static int test_failures_;
static int test_checks_;
#endif

#define TEST_FAIL_(fmt, ...)                                                   \
  do {                                                                         \
    test_failures_++;                                                          \
    fprintf(stderr, "%s:%d: FAIL: " fmt "\n", __FILE__, __LINE__,              \
            __VA_ARGS__);                                                      \
  } while (0)

#define ASSERT_TRUE(c)                                                         \
  do {                                                                         \
    test_checks_++;                                                            \
    if (!(c))                                                                  \
      TEST_FAIL_("%s", #c);                                                    \
  } while (0)

#define ASSERT_EQ_INT(a, b)                                                    \
  do {                                                                         \
    long long a_ = (long long)(a), b_ = (long long)(b);                        \
    test_checks_++;                                                            \
    if (a_ != b_)                                                              \
      TEST_FAIL_("%s == %s: %lld != %lld", #a, #b, a_, b_);                    \
  } while (0)

/* |a - b| <= tol */
#define ASSERT_NEAR(a, b, tol)                                                 \
  do {                                                                         \
    double a_ = (a), b_ = (b), t_ = (tol);                                     \
    test_checks_++;                                                            \
    if (!(fabs(a_ - b_) <= t_))                                                \
      TEST_FAIL_("%s ~ %s: %.17g vs %.17g (diff %.3g > %.3g)", #a, #b, a_, b_, \
                 fabs(a_ - b_), t_);                                           \
  } while (0)

/* |a - b| <= rtol * max(|a|, |b|, 1) */
#define ASSERT_NEAR_REL(a, b, rtol)                                            \
  do {                                                                         \
    double a_ = (a), b_ = (b), t_ = (rtol);                                    \
    double s_ = fmax(1.0, fmax(fabs(a_), fabs(b_)));                           \
    test_checks_++;                                                            \
    if (!(fabs(a_ - b_) <= t_ * s_))                                           \
      TEST_FAIL_("%s ~ %s: %.17g vs %.17g (rel diff %.3g > %.3g)", #a, #b, a_, \
                 b_, fabs(a_ - b_) / s_, t_);                                  \
  } while (0)

#define TEST_DONE()                                                            \
  do {                                                                         \
    printf("%d checks, %d failures\n", test_checks_, test_failures_);          \
    return test_failures_ ? EXIT_FAILURE : EXIT_SUCCESS;                       \
  } while (0)

#endif
