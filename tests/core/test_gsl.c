/*
 * test_gsl.c: the library keeps GSL from aborting without being asked.
 * GSL's handler is per process and is set once, so each claim runs in a
 * child process of its own.
 */
#include <sys/wait.h>
#include <unistd.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>

#include "stickslip.h"
#include "test.h"

static const ss_params PAPER = {0.2, 4.0, 0.0724, 0.6178, 1.0};

/* A GSL call that reports an error through the handler: an LU
 * decomposition with a permutation of the wrong length (GSL_EBADLEN). */
static int lu_error(void) {
  gsl_matrix *a = gsl_matrix_calloc(2, 2);
  gsl_permutation *p = gsl_permutation_alloc(3);
  int sign, rc = gsl_linalg_LU_decomp(a, p, &sign);
  gsl_permutation_free(p);
  gsl_matrix_free(a);
  return rc;
}

static int handled;
static void own_handler(const char *reason, const char *file, int line,
                        int err) {
  (void)reason;
  (void)file;
  (void)line;
  (void)err;
  handled++;
}

/* Run @a fn in a child; its exit status, or -1 if it died (an abort). */
static int in_child(int (*fn)(void)) {
  fflush(stdout);
  pid_t pid = fork();
  if (pid == 0)
    _exit(fn());
  int st = 0;
  waitpid(pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* A program that never calls ss_gsl_quiet(): the first model turns the
 * aborting handler off, so a GSL error comes back as a code. */
static int model_quiets_gsl(void) {
  ss_model m;
  if (ss_model_init(&m, &PAPER, NULL) != SS_OK)
    return 2;
  return lu_error() == GSL_EBADLEN ? 0 : 3;
}

/* A handler the program installed first stays in place. */
static int own_handler_kept(void) {
  ss_model m;
  gsl_set_error_handler(own_handler);
  if (ss_model_init(&m, &PAPER, NULL) != SS_OK)
    return 2;
  ss_gsl_quiet();
  return lu_error() == GSL_EBADLEN && handled == 1 ? 0 : 3;
}

/* The control: without the library GSL's default handler aborts, so the
 * first claim above is not true by accident. */
static int default_aborts(void) { return lu_error() == GSL_EBADLEN ? 0 : 3; }

int main(void) {
  /* EVIDENCE: stickslip.h "Errors": the first ss_model_init() turns GSL's
   * aborting handler off */
  ASSERT_EQ_INT(in_child(model_quiets_gsl), 0);
  /* EVIDENCE: stickslip.h ss_gsl_quiet: a handler the program installed is
   * left in place */
  ASSERT_EQ_INT(in_child(own_handler_kept), 0);
  ASSERT_EQ_INT(in_child(default_aborts), -1);
  TEST_DONE();
}
