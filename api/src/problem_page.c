/*
 * problem_page.c: the page of each problem type, GET /problems/<type>
 * (RFC 9457 section 3.1.1: a type URI that a person can open to learn what
 * the problem means).  A page tells, in the request's own terms, what the
 * problem means and how to change the request so that it is answered; its
 * HTTP statuses come from API_PROBLEM_MAP, the one list of problem types.
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "arena.h"
#include "problem.h"
#include "values.h"
#include "writer.h"

/*
 * The texts of the pages: one row per type of API_PROBLEM_MAP (a type that
 * two rows share, limit-exceeded, has one page).  api_endpoints holds the
 * two lists against each other, and every "/problems/" the sources write
 * against this one.
 *     type        title        what it means        how to fix the request
 */
#define API_PROBLEM_PAGES(X)                                                   \
  X("invalid-json", "The body is not JSON",                                    \
    "The request body is empty, is not valid JSON, or nests arrays and "       \
    "objects deeper than the limit max_depth. The detail gives the line and "  \
    "column where reading stopped.",                                           \
    "Send one JSON object as the body, with Content-Type: application/json. "  \
    "Check the text near the line and column named, and flatten a document "   \
    "nested deeper than max_depth levels.")                                    \
  X("bad-request", "The request is not well formed",                           \
    "The request cannot be read as HTTP the way the daemon reads it: "         \
    "conflicting framing (two Content-Length headers, or Content-Length with " \
    "Transfer-Encoding), a request without Host, or a path parameter that "    \
    "is not of its form, such as a job id that is not 32 lowercase hex "       \
    "digits.",                                                                 \
    "Send one Content-Length or chunked encoding, not both, and a Host "       \
    "header; take a job's id from the Location header of the answer that "     \
    "made it.")                                                                \
  X("not-found", "No such resource",                                           \
    "The path names no endpoint, no problem type, or a job that this daemon "  \
    "does not have (dismissed, expired after --job-ttl, or never made here).", \
    "Check the path against GET /openapi.json; a batch item's path must be "   \
    "one of the computing endpoints. Ask GET /jobs for the jobs the daemon "   \
    "keeps.")                                                                  \
  X("method-not-allowed", "The path does not take this method",                \
    "The path exists but does not take the method sent: the computing "        \
    "endpoints take POST, the others GET. The Allow header names the "         \
    "methods the path takes.",                                                 \
    "Send the request again with a method named in Allow.")                    \
  X("limit-exceeded", "The request is over a limit",                           \
    "The request asks for more than one of the daemon's limits allows: its "   \
    "body's size (413), or its samples, events, horizon, compute time, batch " \
    "items, map or basin cells (422). The member \"limit\" names the limit "   \
    "and \"limit_value\" gives its value.",                                    \
    "Ask for less: fewer samples or a coarser tolerance, a shorter t_end, a "  \
    "smaller grid, fewer items per batch; or split the work into several "     \
    "requests, or send it as a job (Prefer: respond-async), which has limits " \
    "of its own. An operator raises a limit with its flag (max_seconds: "      \
    "--max-seconds; stickslipd --help).")                                      \
  X("unsupported-media-type", "The body is not sent as JSON",                  \
    "A computing request's body must be sent with Content-Type: "              \
    "application/json and without a content coding.",                          \
    "Send the header Content-Type: application/json, and send the body "       \
    "uncompressed (no Content-Encoding, or identity).")                        \
  X("invalid-type", "A field has the wrong JSON type",                         \
    "A field is of another JSON type than the contract says: a string where "  \
    "a number is wanted, an object where an array is, a fraction where a "     \
    "count is. The member \"pointer\" names the field (a JSON Pointer into "   \
    "the body).",                                                              \
    "Give the field named by \"pointer\" the type GET /openapi.json shows "    \
    "for it: numbers unquoted, arrays of the length named.")                   \
  X("invalid-value", "A value is outside its domain",                          \
    "A field has the right type but a value the model or the endpoint does "   \
    "not take: a parameter outside its domain (0 < chi < 1, eta > 0, "         \
    "0 < us < ur, V > 0; for physical units every value > 0 and Fs < Fr), a "  \
    "state inconsistent with its mode, a range that excludes its start. The "  \
    "detail is written in the units the request used, and \"pointer\" names "  \
    "the field.",                                                              \
    "Change the value named by \"pointer\" as the detail says. Physical "      \
    "values that differ by many orders of magnitude can give a "               \
    "dimensionless parameter outside its domain: the detail then gives the "   \
    "formula that made it.")                                                   \
  X("missing-field", "A required field is missing",                            \
    "The body lacks a field that the endpoint requires, such as \"params\" "   \
    "(or \"physical\") or \"t_end\". The member \"pointer\" names it.",        \
    "Add the field named by \"pointer\"; GET /openapi.json lists each "        \
    "endpoint's required fields.")                                             \
  X("unknown-field", "A field is not one the endpoint takes",                  \
    "The body has a field the endpoint does not know, often a misspelt name "  \
    "(\"Chi\" for \"chi\"). Unknown fields are refused rather than ignored, "  \
    "so that a typo never falls back silently to a default.",                  \
    "Remove or rename the field named by \"pointer\"; GET /openapi.json "      \
    "lists the fields each endpoint takes.")                                   \
  X("no-convergence", "The solver did not converge",                           \
    "A root finder of the core stopped without a solution: the orbit "         \
    "equations from the guess given, or a continuation step, did not "         \
    "converge to machine precision.",                                          \
    "Give another guess (the durations of a nearby orbit, from POST /orbit "   \
    "without a guess), or a shorter range or step for a continuation.")        \
  X("client-closed-request", "The client went away",                           \
    "The client closed the connection before its answer was ready, and the "   \
    "computation was stopped. This status (499) is written to the access "     \
    "log; a client that went away does not read it.",                          \
    "Wait for the answer, with a client timeout longer than the "              \
    "computation; a long computation is better sent as a job (Prefer: "        \
    "respond-async) and its results fetched later.")                           \
  X("internal", "Internal error",                                              \
    "The daemon met a state it should never reach: a bug, not a fault of "     \
    "the request. The daemon logs a line for it.",                             \
    "Report the request and its request_id (the X-Request-Id header) to the "  \
    "maintainers; the same request may be answered after the bug is fixed.")   \
  X("overloaded", "Too many computations waiting",                             \
    "This client already has as many computations waiting as --client-queue "  \
    "allows; the other clients are not held up by it.",                        \
    "Retry after the Retry-After header's seconds, send fewer requests at "    \
    "once, or put many computations in one POST /batch.")                      \
  X("out-of-memory", "Out of memory",                                          \
    "The answers and bodies in flight hold the daemon's memory budget "        \
    "(--memory-budget), or this client's share of it, or an allocation "       \
    "failed.",                                                                 \
    "Retry after the Retry-After header's seconds, or ask for a smaller "      \
    "answer (fewer samples, a smaller grid, fewer fields).")                   \
  X("shutting-down", "The daemon is shutting down",                            \
    "The daemon received SIGTERM: it finishes the requests in flight and "     \
    "answers the others with this problem.",                                   \
    "Send the request again to another replica, or to this address once "      \
    "the daemon has restarted.")                                               \
  X("store-unavailable", "Jobs cannot be stored now",                          \
    "The request asked to run as a job (Prefer: respond-async) but the job "   \
    "store cannot take it: it cannot be opened or written, or the "            \
    "PostgreSQL server is unreachable.",                                       \
    "Send the request without Prefer: respond-async to have it answered at "   \
    "once, or retry later; an operator checks --job-store and the daemon's "   \
    "log.")

typedef struct page {
  const char *type, *title, *meaning, *fix;
} page;

static const page PAGES[] = {
#define API_PAGE_ROW(type, title, meaning, fix) {type, title, meaning, fix},
    API_PROBLEM_PAGES(API_PAGE_ROW)
#undef API_PAGE_ROW
};
#define N_PAGES (sizeof PAGES / sizeof PAGES[0])

/* The types of API_PROBLEM_MAP, in its order, one per row. */
static const char *const KIND_TYPES[API_P_COUNT] = {
#define API_KIND_TYPE(name, status, type, title) type,
    API_PROBLEM_MAP(API_KIND_TYPE)
#undef API_KIND_TYPE
};

const char *api_problem_type(api_problem_kind kind) {
  return (unsigned)kind < API_P_COUNT ? KIND_TYPES[kind] : NULL;
}

size_t api_problem_page_count(void) { return N_PAGES; }

const char *api_problem_page_type(size_t i) {
  return i < N_PAGES ? PAGES[i].type : NULL;
}

/* @a s with & < > " escaped for HTML. */
static void html_text(api_wbuf *b, const char *s) {
  for (size_t run = 0, i = 0;; i++) {
    const char *esc = s[i] == '&'   ? "&amp;"
                      : s[i] == '<' ? "&lt;"
                      : s[i] == '>' ? "&gt;"
                      : s[i] == '"' ? "&quot;"
                                    : NULL;
    if (!esc && s[i])
      continue;
    api__w_put(b, s + run, i - run);
    if (!esc)
      return;
    api__w_put(b, esc, strlen(esc));
    run = i + 1;
  }
}

/* The page as HTML: a document a browser shows as it is. */
static char *html_page(const page *p, const int *status, int n_status) {
  api_wbuf b = {NULL, 0, 0, 0};
  API_W_LIT(&b, "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n"
                "<meta charset=\"utf-8\">\n<title>");
  html_text(&b, p->title);
  API_W_LIT(&b, " - stickslipd</title>\n</head>\n<body>\n<h1>");
  html_text(&b, p->title);
  API_W_LIT(&b, "</h1>\n<p><code>/problems/");
  html_text(&b, p->type);
  API_W_LIT(&b, "</code>, HTTP");
  for (int i = 0; i < n_status; i++) {
    char num[16];
    int len = snprintf(num, sizeof num, "%s %d", i ? "," : "", status[i]);
    api__w_put(&b, num, (size_t)len);
  }
  API_W_LIT(&b, "</p>\n<h2>What it means</h2>\n<p>");
  html_text(&b, p->meaning);
  API_W_LIT(&b, "</p>\n<h2>How to fix the request</h2>\n<p>");
  html_text(&b, p->fix);
  API_W_LIT(&b, "</p>\n<p>The problem's body (application/problem+json) "
                "names the field at fault in <code>pointer</code> and the "
                "case in <code>detail</code>. The contract: <a "
                "href=\"/openapi.json\">/openapi.json</a>.</p>\n</body>\n"
                "</html>\n");
  if (b.oom) {
    free(b.p);
    return NULL;
  }
  return b.p;
}

/* The page as JSON: {"type", "title", "status": [...], "meaning", "fix"}. */
static char *json_page(const page *p, const int *status, int n_status) {
  char type[96];
  json_t *o = json_object(), *st = json_array();
  snprintf(type, sizeof type, "/problems/%s", p->type);
  for (int i = 0; i < n_status; i++)
    json_array_append_new(st, json_integer(status[i]));
  api__set(o, "type", json_string(type));
  api__set(o, "title", json_string(p->title));
  api__set(o, "status", st);
  api__set(o, "meaning", json_string(p->meaning));
  api__set(o, "fix", json_string(p->fix));
  char *s = api__json_dumps(o, JSON_COMPACT | JSON_ENSURE_ASCII);
  json_decref(o);
  return s;
}

int api_problem_page(const char *type, int html, api_response *out) {
  const page *p = NULL;
  int status[API_P_COUNT], n = 0;
  memset(out, 0, sizeof *out);
  for (size_t i = 0; i < N_PAGES && !p; i++)
    if (!strcmp(type, PAGES[i].type))
      p = &PAGES[i];
  /* its statuses, each once, in the table's order */
  for (int k = 0; p && k < API_P_COUNT; k++) {
    int s = api_problem_status((api_problem_kind)k), seen = 0;
    for (int i = 0; i < n; i++)
      seen |= status[i] == s;
    if (!strcmp(KIND_TYPES[k], type) && !seen)
      status[n++] = s;
  }
  if (!p || !n) {
    api_problem(out, API_P_NOT_FOUND,
                "no such problem type; every type a problem names is under "
                "/problems/",
                NULL, NULL, 0);
    return out->status;
  }
  out->body = html ? html_page(p, status, n) : json_page(p, status, n);
  if (!out->body) {
    api_problem(out, API_P_OUT_OF_MEMORY, "out of memory", NULL, NULL, 0);
    return out->status;
  }
  out->status = 200;
  out->len = strlen(out->body);
  out->held = out->len;
  out->content_type = html ? "text/html; charset=utf-8" : "application/json";
  return 200;
}
