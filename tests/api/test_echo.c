/*
 * test_echo.c: the "input" of every answer, written as text from the
 * decoded request (api__echo_raw), against the same echo built as a tree
 * of values and dumped by the answer's writer (api__echo and
 * api__params_echo, api__echo_as_tree set): the two must be the same bytes.
 *
 * Each api case (tests/api/cases/<endpoint>-<name>/request.json, with its
 * limits.json if it has one) is answered both ways; where both answers are
 * 200 their "input" members are compared byte for byte, and the answers'
 * texts too once that member is taken out of each (the rest of an answer
 * must not change with how its echo is written; the few answers that tell
 * a time they measured are left out of that second check).  Each case must
 * answer the same status both ways.
 * The contract's request examples (api/openapi.json) are answered the same
 * way.
 * Usage: test_echo api-cases-dir openapi.json
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "case_files.h"
#include "decode.h"
#include "stickslip.h"
#include "stickslip_api.h"
#include "test.h"

/* A check that counts, with a message of its own on failure. */
#define CHECK_MSG(c, ...)                                                      \
  do {                                                                         \
    test_checks_++;                                                            \
    if (!(c))                                                                  \
      TEST_FAIL_(__VA_ARGS__);                                                 \
  } while (0)

/* The top-level "input" member of answer @a a: its value, from after
 * "input": to the "," before the "units" that api__answer writes after
 * it, or, in a map's last line, to the "}\n" that ends it.  NULL when there
 * is none. */
static const char *input_of(const char *a, size_t *n) {
  const char *k = NULL, *p = a, *u;
  size_t len = strlen(a);
  while ((p = strstr(p, "\"input\":")) != NULL)
    k = p++;
  if (!k)
    return NULL;
  if ((u = strstr(k, ",\"units\":")) != NULL)
    *n = (size_t)(u - (k + 8));
  else if (len >= 2 && !strcmp(a + len - 2, "}\n"))
    *n = (size_t)(a + len - 2 - (k + 8));
  else
    return NULL;
  return k + 8;
}

static int compared, whole, physical, custom;
static unsigned endpoints_seen; /* bit i: endpoint i answered 200 */

/* Request @a req (of @a len bytes) to endpoint @a ep, answered both ways. */
static void check(size_t ep, const char *req, size_t len,
                  const api_limits *limp, const char *name) {
  api_limits lim = *limp;
  api_response text, tree;
  api__echo_as_tree = 0;
  int st_text = api_handle(ep, req, len, &lim, NULL, &text);
  api__echo_as_tree = 1;
  int st_tree = api_handle(ep, req, len, &lim, NULL, &tree);
  api__echo_as_tree = 0;
  CHECK_MSG(st_text == st_tree, "%s: status %d written, %d from the tree", name,
            st_text, st_tree);
  if (st_text == 200 && st_tree == 200 && text.body && tree.body) {
    size_t na = 0, nb = 0;
    const char *a = input_of(text.body, &na), *b = input_of(tree.body, &nb);
    CHECK_MSG(a && b, "%s: an answer without its input", name);
    if (a && b) {
      compared++;
      CHECK_MSG(na == nb && memcmp(a, b, na) == 0,
                "%s: the echo written\n  %.*s\nand from the tree\n  %.*s", name,
                (int)na, a, (int)nb, b);
      physical += strstr(req, "\"physical\"") != NULL;
      custom += strstr(req, "\"samples\"") != NULL;
      /* the rest of the answer, where it tells no time it measured */
      if (!strstr(text.body, "\"seconds\"")) {
        size_t pa = (size_t)(a - text.body), pb = (size_t)(b - tree.body);
        CHECK_MSG(pa == pb && memcmp(text.body, tree.body, pa) == 0 &&
                      strcmp(a + na, b + nb) == 0,
                  "%s: the answers differ outside their echo", name);
        whole++;
      }
    }
  }
  if (st_text == 200)
    endpoints_seen |= 1u << ep;
  api_response_free(&text);
  api_response_free(&tree);
}

static void check_case(const char *dir, const char *name) {
  char path[4096];
  size_t len, ep = case_endpoint(name);
  if (ep == api_endpoint_count())
    return;
  snprintf(path, sizeof path, "%s/%s/request.json", dir, name);
  char *req = case_slurp(path, &len);
  if (!req)
    return;
  api_limits lim;
  api_limits_default(&lim);
  snprintf(path, sizeof path, "%s/%s/limits.json", dir, name);
  CHECK_MSG(case_limits(path, &lim) == 0, "%s: bad limits.json", name);
  check(ep, req, len, &lim, name);
  free(req);
}

/* Every request example of the contract's POST paths. */
static void check_contract(const char *openapi) {
  json_t *spec = json_load_file(openapi, 0, NULL), *ops;
  const char *path;
  api_limits lim;
  api_limits_default(&lim);
  CHECK_MSG(spec != NULL, "cannot read %s", openapi);
  json_object_foreach(json_object_get(spec, "paths"), path, ops) {
    size_t ep;
    json_t *ex = json_object_get(
        json_object_get(
            json_object_get(
                json_object_get(json_object_get(ops, "post"), "requestBody"),
                "content"),
            "application/json"),
        "examples");
    const char *name;
    json_t *e;
    if (!ex || api_route("POST", path, &ep) != 200 ||
        api_endpoint_at(ep)->run_class != API_RUN_COMPUTE)
      continue;
    json_object_foreach(ex, name, e) {
      char *body = json_dumps(json_object_get(e, "value"), JSON_COMPACT);
      char label[256];
      snprintf(label, sizeof label, "%s %s", path, name);
      if (body)
        check(ep, body, strlen(body), &lim, label);
      free(body);
    }
  }
  json_decref(spec);
}

int main(int argc, char **argv) {
  if (argc < 3)
    return 2;
  ss_gsl_quiet();
  DIR *d = opendir(argv[1]);
  if (!d) {
    fprintf(stderr, "%s: no such directory\n", argv[1]);
    return 2;
  }
  struct dirent *e;
  while ((e = readdir(d)) != NULL)
    if (e->d_name[0] != '.')
      check_case(argv[1], e->d_name);
  closedir(d);
  check_contract(argv[2]);
  printf("%d answers' echoes compared (%d with physical parameters, %d with "
         "samples), %d answers whole\n",
         compared, physical, custom, whole);
  /* the cases hold answers of every computing endpoint, some in physical
   * units and some with samples: a directory that lost them proves little */
  unsigned computing = 0;
  for (size_t i = 0; i < api_endpoint_count(); i++)
    if (api_endpoint_at(i)->run_class == API_RUN_COMPUTE)
      computing |= 1u << i;
  CHECK_MSG(compared >= 25 && physical >= 2 && custom >= 2 &&
                endpoints_seen == computing,
            "too few answers compared (%d; endpoints %#x of %#x)", compared,
            endpoints_seen, computing);
  TEST_DONE();
}
