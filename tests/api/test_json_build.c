/*
 * test_json_build.c: the tree built straight from text the scan vouches for
 * (api__json_build, scan.c) against jansson's json_loadb of the same text.
 *
 * For every request body the repository holds (the api cases and the fuzz
 * corpus) and for texts made to reach each kind of value: when the builder
 * gives a tree, jansson must give one too, and the two must be equal, type
 * for type (an integer is not a real), in the same order, every real the
 * same double (their texts dumped with 17 digits compared).  Texts jansson
 * refuses, and those it reads differently than plainly (escapes \u, UTF-8,
 * numbers past the scan's bounds, duplicate keys, a scalar at the top,
 * text after the value), must be left to jansson: no tree.
 * Usage: test_json_build api-cases-dir fuzz-corpus-dir
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <locale.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "scan.h"
#include "test.h"

static int built, compared;

static char *dump(const json_t *j) {
  return json_dumps(j,
                    JSON_COMPACT | JSON_ENCODE_ANY | JSON_REAL_PRECISION(17));
}

/* The builder's tree of @a text (of @a n bytes) against jansson's. */
static void check(const char *text, size_t n, const char *name) {
  json_t *b = api__json_build(text, text + n, 64);
  json_error_t e;
  json_t *j = json_loadb(text, n, JSON_REJECT_DUPLICATES, &e);
  compared++;
  if (b) {
    built++;
    char *db = dump(b), *dj = j ? dump(j) : NULL;
    if (!j || !json_equal(b, j) || !db || !dj || strcmp(db, dj) != 0)
      TEST_FAIL_("%s: built %s, jansson %s", name, db ? db : "?",
                 dj ? dj : e.text);
    test_checks_++;
    free(db);
    free(dj);
  }
  json_decref(b);
  json_decref(j);
}

static void check_str(const char *text, int must_build) {
  int before = built;
  check(text, strlen(text), text);
  if (must_build != (built > before))
    TEST_FAIL_("%s: %s", text, must_build ? "not built" : "built");
  test_checks_++;
}

static void check_dir(const char *dir, const char *file) {
  DIR *d = opendir(dir);
  if (!d) {
    TEST_FAIL_("cannot open %s", dir);
    return;
  }
  struct dirent *de;
  while ((de = readdir(d)) != NULL) {
    if (de->d_name[0] == '.')
      continue;
    char path[4096];
    snprintf(path, sizeof path, "%s/%s%s%s", dir, de->d_name, file ? "/" : "",
             file ? file : "");
    FILE *f = fopen(path, "rb");
    if (!f)
      continue;
    char *buf = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&buf, &len);
    char chunk[65536];
    size_t k;
    while ((k = fread(chunk, 1, sizeof chunk, f)) > 0)
      fwrite(chunk, 1, k, m);
    fclose(f);
    fclose(m);
    check(buf, len, path);
    free(buf);
  }
  closedir(d);
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: %s api-cases-dir fuzz-corpus-dir\n", argv[0]);
    return 2;
  }
  /* plain texts of every kind of value: built */
  const char *plain[] = {
      "{}",
      "[]",
      " {\"a\" : 1 ,\"b\":[ ] ,\"c\":{ }}\n",
      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1},"
      "\"guess\":{\"durations\":[4.5,2.717,3.0536]},\"finite_difference\":"
      "false}",
      "[0,-0,-0.0,1E5,1e-5,2.5E+10,-1.25e-249,123456789012345678,"
      "-123456789012345678,0.1,0.30000000000000004,"
      "123456789012345678901234567890.5]",
      "[true,false,null,\"\",\"x\"]",
      "{\"s\":\"a\\\"b\\\\c\\/d\\be\\ff\\ng\\rh\\ti\"}",
      "[[[[[[1]]]]]]",
      "{\"a\":{\"b\":{\"c\":[1,{\"d\":\"e\"}]}}}",
  };
  for (size_t i = 0; i < sizeof plain / sizeof plain[0]; i++)
    check_str(plain[i], 1);
  /* left to jansson, valid or not */
  const char *other[] = {
      "1",
      "\"top\"",
      "{\"a\":1} x",
      "{\"a\":1,\"a\":2}",
      "{\"a\":{\"b\":1,\"b\":1}}",
      "{\"u\":\"\\u0041\"}",
      "{\"u\":\"\\u0000\"}",
      "{\"u\":\"\\ud800\"}",
      "{\"k\\n\":1}",
      "{\"e\":\"\xc3\xa9\"}",
      "[1e400]",
      "[1e250]",
      "[1e0001]",
      "[5e-555555555555555555555555555555555555555555555555555555555555552]",
      "{\"chi\":2E+99999999999}",
      "[12345678901234567890]",
      "[0.000000000000000000000000000000000000000000000000000000000000000"
      "000000000000000000000001]",
      "[01]",
      "[1.]",
      "[.5]",
      "[+1]",
      "{\"a\":1,}",
      "[1,]",
      "{\"a\" 1}",
      "[tru]",
      "{",
      "",
  };
  for (size_t i = 0; i < sizeof other / sizeof other[0]; i++)
    check_str(other[i], 0);
  /* the numbers do not follow the process's locale */
  if (setlocale(LC_NUMERIC, "de_DE.UTF-8") ||
      setlocale(LC_NUMERIC, "fr_FR.UTF-8")) {
    check_str("[0.5,2.25e3]", 1);
    printf("numbers read in a locale whose point is a comma\n");
  } else {
    printf("no locale whose point is a comma is installed: not checked\n");
  }
  setlocale(LC_NUMERIC, "C");
  int before = built;
  check_dir(argv[1], "request.json");
  check_dir(argv[2], NULL);
  printf("%d texts: %d built, each equal to jansson's tree\n", compared, built);
  /* the repository's own requests are mostly plain: the builder reads them */
  ASSERT_TRUE(built - before > 100);
  TEST_DONE();
}
