/*
 * docs.h: the user's guide (docs/, built by mkdocs) as the daemon serves it
 * at /docs/: a table of its files made at build time by scripts/docs.py
 * (docs_embed.c), or an empty one when mkdocs was not there to build it.
 */
#ifndef SS_API_DOCS_H
#define SS_API_DOCS_H

#include <stddef.h>

typedef struct api__doc_file {
  const char *path;  /* under the site's root: "index.html", "css/base.css" */
  const char *ctype; /* its media type */
  const char *etag;  /* a validator: 16 hex digits of its SHA-1, quoted */
  const char *bytes; /* its contents, NUL-terminated */
  size_t len;
} api__doc_file;

/* The files, sorted by path, then a row of NULLs; api__n_docs of them (0:
 * no guide in this build). */
extern const api__doc_file api__docs[];
extern const size_t api__n_docs;

#endif
