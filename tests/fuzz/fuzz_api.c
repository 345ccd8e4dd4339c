/*
 * fuzz_api.c: the request decoder and the endpoints on arbitrary bytes.
 *
 * Every input, for every computing endpoint and for /batch, must give a
 * 200, 400 or 422 whose body is valid JSON (so with no NaN or Infinity); a
 * batch's answer must be lines of valid JSON, each item's status one of
 * those or 404 (no such path); all within small compute limits.  Anything
 * else aborts.  Built as a libFuzzer target with clang
 * (-DSTICKSLIP_FUZZ=ON) and, with replay.c, as an ordinary test that runs
 * the stored corpus (tests/fuzz/corpus).
 */
#include <jansson.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "stickslip.h"
#include "stickslip_api.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Abort unless @a t (of @a n bytes) is JSON whose "status", when it has
 * one, is 200, 400 or 422, or 404 for a batch's item (no such path). */
static void check_json(size_t ep, const char *t, size_t n, int item) {
  json_error_t je;
  json_t *j = t ? json_loadb(t, n, 0, &je) : NULL;
  /* jansson refuses NaN and Infinity tokens, so a body it parses has
   * none (the words may appear inside strings, quoting the input) */
  if (!j) {
    fprintf(stderr, "endpoint %zu: bad body: %.300s\n", ep, t ? t : "(none)");
    abort();
  }
  json_t *st = json_object_get(j, "status");
  json_int_t code = json_integer_value(st);
  if (json_is_integer(st) && code != 200 && code != 400 && code != 422 &&
      !(item && code == 404)) {
    fprintf(stderr, "endpoint %zu: a line with status %d: %.300s\n", ep,
            (int)json_integer_value(st), t);
    abort();
  }
  json_decref(j);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static int init;
  api_limits lim;
  if (!init) {
    ss_gsl_quiet();
    init = 1;
  }
  api_limits_default(&lim);
  lim.max_samples = 2000;
  lim.max_events = 20000;
  lim.max_event_list = 2000;
  lim.max_horizon = 1e4;
  lim.max_seconds = 0.2;
  lim.max_orbits = 4;
  lim.max_batch_items = 4;
  for (size_t ep = 0; ep < api_endpoint_count(); ep++) {
    int batch = api_endpoint_at(ep)->run_class == API_RUN_BATCH;
    if (api_endpoint_at(ep)->run_class != API_RUN_COMPUTE && !batch)
      continue;
    api_response r;
    int st = api_handle(ep, (const char *)data, size, &lim, NULL, &r);
    if (st != 200 && st != 400 && st != 422) {
      fprintf(stderr, "endpoint %zu answered %d: %s\n", ep, st,
              r.body ? r.body : "(no body)");
      abort();
    }
    if (batch && st == 200) {
      /* NDJSON: each line JSON, each item's status one of those */
      const char *t = r.body, *end = r.body + r.len, *e;
      for (; t < end; t = e + 1) {
        if (!(e = memchr(t, '\n', (size_t)(end - t))))
          abort(); /* every line ends with a newline */
        check_json(ep, t, (size_t)(e - t), 1);
      }
    } else {
      check_json(ep, r.body, r.body ? strlen(r.body) : 0, 0);
    }
    api_response_free(&r);
  }
  return 0;
}
