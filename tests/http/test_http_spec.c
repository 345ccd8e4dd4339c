/*
 * test_http_spec.c (CTest http_spec): the contract's examples (GET
 * /openapi.json) replayed: each is what the daemon answers.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixture.h"

/* @a j without its "seconds" (the time taken), at any depth: a /map item
 * of a batch has its map's last line in its body. */
static void drop_seconds(json_t *j) {
  const char *k;
  json_t *v;
  size_t i;
  json_object_del(j, "seconds");
  json_object_foreach(j, k, v) drop_seconds(v);
  json_array_foreach(j, i, v) drop_seconds(v);
}

/* The lines of NDJSON text @a t as an array ordered by "index" (a batch's
 * items; a map's cells, whose index is an array, in their order), the line
 * without one last, "seconds" dropped; NULL when a line is not JSON. */
static json_t *ndjson_sorted(const char *t) {
  json_t *a = json_array(), *last = NULL;
  for (const char *e; t && *t; t = e + 1) {
    if (!(e = strchr(t, '\n')))
      e = t + strlen(t);
    json_t *l = json_loadb(t, (size_t)(e - t), 0, NULL);
    if (!l) {
      json_decref(a);
      json_decref(last);
      return NULL;
    }
    drop_seconds(l);
    json_t *ix = json_object_get(l, "index");
    if (json_is_array(ix)) { /* a map's cells, in the order written */
      json_array_append_new(a, l);
    } else if (!json_is_integer(ix)) {
      json_decref(last);
      last = l;
    } else {
      size_t i = (size_t)json_integer_value(ix);
      while (json_array_size(a) <= i)
        json_array_append_new(a, json_null());
      json_array_set_new(a, i, l);
    }
    if (!*e)
      break;
  }
  if (last)
    json_array_append_new(a, last);
  return a;
}

/* EVIDENCE: docs/api/index.md: the contract is api/openapi.json, served at
 * GET /openapi.json.  That its examples are what the daemon answers is not
 * stated in README; this test replays them. */
/* Replay example @a name of @a path (its request @a body) asking for
 * @a media: the answer must be @a want with status @a want_status. */
static void replay(const char *path, const char *name, const char *body,
                   const char *media, json_t *want, int want_status) {
  char accept[128];
  http_resp rr;
  snprintf(accept, sizeof accept, "Accept: %s\r\n", media);
  ASSERT_EQ_INT(raw_with(PORT, "POST", path, accept, body, &rr), 0);
  ASSERT_EQ_INT(rr.status, want_status);
  /* an NDJSON example is its text: the same lines, in any order, all
   * but the time taken */
  json_t *got = json_is_string(want) ? ndjson_sorted(rr.body)
                                     : json_loads(rr.body, 0, NULL);
  /* a problem names its request, which differs every time */
  if (json_is_object(got))
    json_object_del(got, "request_id");
  json_t *want_j =
      json_is_string(want) ? ndjson_sorted(json_string_value(want)) : NULL;
  if (want_j)
    want = want_j;
  char where[256] = "";
  if (!got || !same_json(want, got, 1e-7, where, sizeof where))
    TEST_FAIL_("spec example %s %s (%s) differs from the answer at %s", path,
               name, media, where);
  test_checks_++;
  json_decref(got);
  json_decref(want_j);
  http_free(&rr);
}

static void test_spec_examples(void) {
  http_resp r;
  ASSERT_EQ_INT(http_do(PORT, "GET", "/openapi.json", NULL, NULL, &r), 0);
  json_t *spec = json_loads(r.body, 0, NULL);
  http_free(&r);
  ASSERT_TRUE(spec != NULL);
  const char *path;
  json_t *item;
  int replayed = 0;
  json_object_foreach(json_object_get(spec, "paths"), path, item) {
    json_t *post = json_object_get(item, "post");
    if (!post)
      continue;
    json_t *reqex = json_object_get(
        json_object_get(
            json_object_get(json_object_get(post, "requestBody"), "content"),
            "application/json"),
        "examples");
    const char *name;
    json_t *ex;
    json_object_foreach(reqex, name, ex) {
      /* each response example of the same name, asked in its media type
       * (an endpoint may answer in more than one: Accept chooses) */
      const char *code;
      json_t *resp;
      int found = 0;
      char *body = json_dumps(json_object_get(ex, "value"), JSON_COMPACT);
      json_object_foreach(json_object_get(post, "responses"), code, resp) {
        const char *ct;
        json_t *media;
        json_object_foreach(json_object_get(resp, "content"), ct, media) {
          json_t *e = json_object_get(json_object_get(media, "examples"), name);
          if (e) {
            found++;
            replay(path, name, body, ct, json_object_get(e, "value"),
                   atoi(code));
            replayed++;
          }
        }
      }
      ASSERT_TRUE(found > 0);
      free(body);
    }
  }
  printf("spec: %d examples replayed\n", replayed);
  ASSERT_TRUE(replayed >= 8);
  json_decref(spec);
}

int main(int argc, char **argv) {
  daemon_proc d;
  if (fixture_init(argc, argv))
    return 2;
  fixture_daemon_start(&d);
  test_spec_examples();
  fixture_daemon_stop(&d);
  TEST_DONE();
}
