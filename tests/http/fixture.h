/*
 * fixture.h: what the HTTP tests share.  Each topic is an executable of its
 * own, tests/http/test_http_<topic>.c, registered as the CTest
 * http_<topic>; it starts its own daemons on free ports (--port 0), so the
 * topics run side by side.  Here: the daemon under test, the requests the
 * topics send, and the checks of a problem answer, all counted by test.h's
 * assertions (one count for the whole executable).
 * Usage of every topic: test_http_<topic> PATH/stickslipd
 */
#ifndef SS_TEST_FIXTURE_H
#define SS_TEST_FIXTURE_H

#include <jansson.h>
#include <sys/types.h>

#include "client.h"
#define TEST_SHARED_COUNTERS
#include "test.h"

/* The daemon binary (argv[1]) and the port of the daemon the helpers below
 * talk to (those that take no port). */
extern const char *BIN;
extern int PORT;

#define PAPER                                                                  \
  "\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1}"
#define JSON "application/json"
/* the stick -> slip point of the paper's orbit: events every few units */
#define X0 "[1.2739277342427062,4.3629277342427093,-0.80748713672430694,1.0]"

/* Computations for the pool tests: LONG needs minutes (it ends only by
 * cancellation or shutdown), MEDIUM about a second, CHEAP microseconds. */
extern const char *const LONG_SIM, *const MEDIUM_SIM, *const CHEAP;

/* The daemon's path from the command line, SIGPIPE ignored: 0, or the exit
 * status of a wrong usage. */
int fixture_init(int argc, char **argv);
/* Start the daemon with its defaults and point PORT at it. */
void fixture_daemon_start(daemon_proc *d);
/* Stop it with SIGTERM (it must exit 0) and remove its log. */
void fixture_daemon_stop(daemon_proc *d);

/* POST @a body to @a path on PORT, expecting status @a want: the answer's
 * JSON (the caller frees it), or NULL. */
json_t *post(const char *path, const char *body, int want);
/* The number at a tiny JSON pointer (/a/0/b) of @a j, or NaN. */
double num(json_t *j, const char *path);
/* The daemon on PORT still answers /health (checked; @a after names what
 * came before). */
void health_ok(const char *after);
/* The problem body of @a r, checked (status @a want, @a type, @a pointer
 * unless NULL), or NULL after a failure. */
json_t *problem_body(const char *name, const http_resp *r, int want,
                     const char *type, const char *pointer);
/* A raw request that must end in a problem (or, with @a mhd_page,
 * libmicrohttpd's own page) and the connection closed. */
void expect_problem_raw(const char *name, const char *raw, size_t len, int want,
                        const char *type, int mhd_page);
/* A request that must get a problem of @a type (and @a pointer, unless
 * NULL): its body (the caller frees it) or NULL. */
json_t *expect_problem(const char *name, const char *method, const char *path,
                       const char *ctype, const char *body, int want,
                       const char *type, const char *pointer);

/* The monotonic clock, seconds. */
double mono(void);
/* Send a POST and return the socket to read the answer from. */
int start(int port, const char *path, const char *body);
/* A counter of the daemon's /metrics, or -1. */
double metric(int port, const char *name);
/* CPU seconds the process has used. */
double cpu_seconds(pid_t pid);

/* The latency of a cheap computation from @a src, and its status. */
typedef struct probe {
  int port, status;
  const char *src;
  double seconds;
} probe;
/* Send CHEAP to /stability from p->src; p->status and p->seconds. */
void *cheap_probe(void *vp);

/* Structural equality with a relative tolerance on numbers; where they
 * differ into @a where. */
int same_json(json_t *a, json_t *b, double rtol, char *where, size_t n);
/* The value of header @a name in the raw response @a raw (into @a out), or
 * NULL. */
const char *header_of(const char *raw, const char *name, char *out, size_t n);
/* A request with extra header lines (each ending in CRLF); the answer in
 * @a r. */
int raw_with(int port, const char *method, const char *path,
             const char *headers, const char *body, http_resp *r);

#endif
