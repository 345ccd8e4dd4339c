/*
 * docs.c: a file of the embedded user's guide by its path under /docs/.
 * The table (docs.h) is sorted by path, so a lookup is a binary search.
 */
#include <stdlib.h>
#include <string.h>

#include "docs.h"
#include "stickslip_api.h"

static int by_path(const void *key, const void *row) {
  return strcmp(key, ((const api__doc_file *)row)->path);
}

int api_docs_built(void) { return api__n_docs > 0; }

const char *api_docs_file(const char *path, size_t *len, const char **ctype,
                          const char **etag) {
  const char *index = "index.html";
  char name[256];
  size_t n = strlen(path);
  /* a directory's page is its index.html */
  if (n == 0 || path[n - 1] == '/') {
    if (n + strlen(index) >= sizeof name)
      return NULL;
    memcpy(name, path, n);
    strcpy(name + n, index);
    path = name;
  }
  const api__doc_file *f =
      bsearch(path, api__docs, api__n_docs, sizeof *api__docs, by_path);
  if (!f)
    return NULL;
  *len = f->len;
  *ctype = f->ctype;
  *etag = f->etag;
  return f->bytes;
}
