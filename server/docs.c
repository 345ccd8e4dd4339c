/*
 * docs.c: the user's guide at /docs/ (api_docs_file: the site mkdocs built,
 * embedded at build time).  GET and HEAD only; a page has a validator and a
 * lifetime as the explorer's files do.  A build without the guide answers
 * 404 saying so.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"

int srv__docs_admit(srv__req *r, const char *url, const char *method) {
  if (strncmp(url, "/docs", 5) || (url[5] && url[5] != '/'))
    return 0;
  if (!api_docs_built()) {
    srv__defer(r, API_P_NOT_FOUND,
               "this stickslipd was built without its user's guide (mkdocs "
               "was not installed when it was built); the guide's sources "
               "are docs/ in the source tree",
               NULL);
    return 1;
  }
  if (!url[5]) {
    srv__defer(r, API_P_NOT_FOUND, "the user's guide is at /docs/", NULL);
    return 1;
  }
  if (!strcmp(method, "OPTIONS")) {
    snprintf(r->preflight, sizeof r->preflight, "GET, OPTIONS");
    return 1;
  }
  if (strcmp(method, "GET") && strcmp(method, "HEAD")) {
    snprintf(r->p_detail, sizeof r->p_detail, "the user's guide takes GET");
    srv__defer(r, API_P_METHOD_NOT_ALLOWED, NULL, "GET");
    return 1;
  }
  r->doc = api_docs_file(url + 6, &r->doc_len, &r->doc_ctype, &r->etag);
  if (!r->doc) {
    r->etag = NULL;
    srv__defer(r, API_P_NOT_FOUND,
               "no such page of the user's guide; its contents are at /docs/",
               NULL);
  }
  return 1;
}

enum MHD_Result srv__docs_answer(struct MHD_Connection *c, srv__req *r) {
  if (srv__not_modified(c, r))
    return srv__send_body(c, r, 304, NULL, 0, r->doc_ctype, 0, NULL, 0);
  char *body = malloc(r->doc_len + 1);
  if (!body)
    return srv__send_problem(c, r, API_P_OUT_OF_MEMORY, "out of memory", NULL,
                             0, NULL);
  memcpy(body, r->doc, r->doc_len + 1);
  return srv__send_body(c, r, 200, body, r->doc_len, r->doc_ctype, 0, NULL, 0);
}
