/*
 * test_case.c: one codec case, without HTTP.  A case is a directory
 * tests/api/cases/<endpoint>-<name>/ with request.json (the body, sent as
 * is), expect.json: {"status": N, "body": {...}}, and optionally
 * limits.json: {"max_seconds": 1e-6, ...}, limits that replace the defaults
 * for this case.  <endpoint> is the label of a computing endpoint in the
 * api's endpoint table.  The expected body is matched as a subset: every
 * key it names must be in the answer with an equal value (numbers to a
 * relative 1e-9); arrays must match in length and element by element.
 * With shape.txt, the answer's text must also be that text once every
 * number is written '#': the keys, their order and the compact form that
 * the writer keeps (the answers are written straight from the core's
 * structs, not dumped from a tree).
 *
 * The same request is then served as a job (job_runner.c: its chunks in
 * reverse order within each stage), and the job's answer must be the
 * synchronous answer byte for byte, but for the times it reports
 * ("seconds"; and a problem's "detail" when the case sets max_seconds, for
 * it tells the time measured): a problem at submission where the
 * synchronous request is refused before it computes, else the failed
 * chunk's problem, else the visible results.
 * Usage: test_case DIR
 */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "case_files.h"
#include "job_runner.h"
#include "stickslip.h"
#include "stickslip_api.h"

static int subset(json_t *want, json_t *got, char *path, size_t n) {
  size_t pl = strlen(path);
  if (json_is_number(want) && json_is_number(got)) {
    double a = json_number_value(want), b = json_number_value(got);
    return fabs(a - b) <= 1e-9 * fmax(1.0, fmax(fabs(a), fabs(b)));
  }
  if (json_typeof(want) != json_typeof(got))
    return 0;
  if (json_is_object(want)) {
    const char *k;
    json_t *v;
    json_object_foreach(want, k, v) {
      snprintf(path + pl, n - pl, "/%s", k);
      json_t *g = json_object_get(got, k);
      if (!g || !subset(v, g, path, n))
        return 0;
      path[pl] = 0;
    }
    return 1;
  }
  if (json_is_array(want)) {
    if (json_array_size(want) != json_array_size(got))
      return 0;
    for (size_t i = 0; i < json_array_size(want); i++) {
      snprintf(path + pl, n - pl, "/%zu", i);
      if (!subset(json_array_get(want, i), json_array_get(got, i), path, n))
        return 0;
      path[pl] = 0;
    }
    return 1;
  }
  return json_equal(want, got);
}

/* Whether the job of request @a req answers @a sync (compared but for
 * "seconds", and a problem's "detail" when @a timed). */
static int same_as_job(size_t ep, const char *req, size_t len,
                       const api_limits *lim, const api_response *sync,
                       int timed) {
  api_response r;
  job_trace t;
  job_answer(ep, req, len, lim, JOB_REVERSE, 0, &r, &t);
  char *a = job_blank(sync->body, sync->len, "seconds");
  char *b = job_blank(r.body ? r.body : "", r.len, "seconds");
  if (timed && sync->status != 200) {
    char *a2 = job_blank(a, strlen(a), "detail");
    char *b2 = job_blank(b, strlen(b), "detail");
    free(a);
    free(b);
    a = a2;
    b = b2;
  }
  int same = r.status == sync->status && !strcmp(a, b) &&
             !strcmp(r.content_type, sync->content_type) && !t.bad_reads &&
             (!t.opened || t.items == t.items_sum);
  if (!same)
    fprintf(stderr,
            "as a job (opened %d, %zu chunks, %d bad reads, content %s): "
            "%d %.2000s\nsynchronous: %d %.2000s\n",
            t.opened, t.chunks, t.bad_reads, r.content_type, r.status, b,
            sync->status, a);
  free(a);
  free(b);
  api_response_free(&r);
  return same;
}

/* The shape of a JSON text: every number written as '#', the rest (keys,
 * their order, strings, nesting, null) as it is. */
static char *shape_of(const char *t) {
  size_t n = strlen(t), j = 0;
  char *s = malloc(n + 1);
  int in_str = 0;
  for (size_t i = 0; s && i < n; i++) {
    char c = t[i];
    if (in_str) {
      s[j++] = c;
      if (c == '\\' && i + 1 < n)
        s[j++] = t[++i];
      else if (c == '"')
        in_str = 0;
    } else if (c == '"') {
      s[j++] = c;
      in_str = 1;
    } else if (strchr("-0123456789", c)) {
      while (i + 1 < n && strchr("-+.eE0123456789", t[i + 1]))
        i++;
      s[j++] = '#';
    } else {
      s[j++] = c;
    }
  }
  if (s)
    s[j] = 0;
  return s;
}

/* The answer's text against shape.txt when the case has one: the keys in
 * their order, compact, the numbers aside (matched above to 1e-9). */
static int same_shape(const char *dir, const char *body) {
  char path[4096];
  size_t len;
  snprintf(path, sizeof path, "%s/shape.txt", dir);
  char *want = case_slurp(path, &len);
  if (!want)
    return 1;
  while (len && want[len - 1] == '\n')
    want[--len] = 0;
  char *got = body ? shape_of(body) : NULL;
  int ok = got && strcmp(got, want) == 0;
  if (!ok)
    fprintf(stderr, "shape: %.2000s\nwanted: %.2000s\n", got ? got : "", want);
  free(got);
  free(want);
  return ok;
}

int main(int argc, char **argv) {
  char path[4096], where[512] = "";
  size_t len, elen;
  if (argc < 2)
    return 2;
  ss_gsl_quiet();
  const char *base = strrchr(argv[1], '/');
  base = base ? base + 1 : argv[1];
  size_t ep = case_endpoint(base);
  if (ep == api_endpoint_count()) {
    fprintf(stderr, "%s: the name must start with a computing endpoint\n",
            base);
    return 2;
  }
  snprintf(path, sizeof path, "%s/request.json", argv[1]);
  char *req = case_slurp(path, &len);
  snprintf(path, sizeof path, "%s/expect.json", argv[1]);
  char *exp = case_slurp(path, &elen);
  json_t *want = exp ? json_loads(exp, 0, NULL) : NULL;
  if (!req || !want) {
    fprintf(stderr, "%s: missing request.json or expect.json\n", base);
    return 2;
  }
  api_limits lim;
  api_limits_default(&lim);
  snprintf(path, sizeof path, "%s/limits.json", argv[1]);
  size_t lim_len;
  char *lim_text = case_slurp(path, &lim_len);
  if (case_limits(path, &lim)) {
    fprintf(stderr, "%s: bad limits.json\n", base);
    return 2;
  }
  api_response r;
  int st = api_handle(ep, req, len, &lim, NULL, &r);
  json_t *got = json_loads(r.body, 0, NULL);
  int ok =
      got && st == (int)json_integer_value(json_object_get(want, "status"));
  if (ok)
    ok = subset(json_object_get(want, "body"), got, where, sizeof where);
  /* EVIDENCE: DESIGN §4 field names are the contract: the text of the
   * answer, written straight from the core's structs, keeps its keys and
   * their order */
  if (ok && !same_shape(argv[1], r.body)) {
    ok = 0;
    snprintf(where, sizeof where, "the shape of shape.txt");
  }
  printf("%s: status %d, %s%s%s\n", base, st, ok ? "as expected" : "differs",
         ok ? "" : " at ", ok ? "" : where);
  if (!ok)
    fprintf(stderr, "answer: %.2000s\n", r.body);
  /* EVIDENCE: stickslip_api.h "Jobs": a job's answer is byte for byte the
   * synchronous answer, but for a time it reports */
  int as_job = same_as_job(ep, req, len, &lim, &r,
                           lim_text && strstr(lim_text, "seconds"));
  printf("%s: as a job, %s\n2 checks, %d failures\n", base,
         as_job ? "the same answer" : "another answer", !ok + !as_job);
  ok = ok && as_job;
  json_decref(got);
  json_decref(want);
  api_response_free(&r);
  free(req);
  free(exp);
  free(lim_text);
  return ok ? 0 : 1;
}
