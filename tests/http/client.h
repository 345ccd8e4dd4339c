/*
 * client.h: a small HTTP/1.1 client over raw sockets for the HTTP tests,
 * able to send malformed requests that a library would refuse to make, and
 * a helper that starts stickslipd on a free port.
 */
#ifndef SS_TEST_CLIENT_H
#define SS_TEST_CLIENT_H

#include <stddef.h>
#include <sys/types.h>

typedef struct http_resp {
  int status;
  char *raw;  /* whole response, NUL-terminated */
  char *body; /* into raw */
  size_t len; /* of body (which may hold NULs: a gzipped answer) */
  char ctype[96];
  char retry_after[16];
  char allow[32];
  int eof;     /* the server closed the connection (not a read timeout) */
  int chunked; /* the body came chunked (it is decoded in body) */
} http_resp;

/* The source address of the calling thread's connections, e.g.
 * "127.0.0.2" (the daemon tells clients apart by address); NULL: any. */
void http_set_source(const char *addr);
/* A connected socket to 127.0.0.1:port, or -1. */
int http_connect(int port);
/* Connect and send @a req; the socket (to read the answer from), or -1. */
int http_send(int port, const char *req, size_t len);
/* Read an answer until the server closes or @a timeout_ms passes without a
 * byte (r->eof tells which); closes @a fd.  0 when a response was read. */
int http_read(int fd, int timeout_ms, http_resp *r);
/* The text of a request with Connection: close (malloc'd), its length in
 * *len. */
char *http_request(const char *method, const char *path, const char *ctype,
                   const char *body, size_t *len);
/* Send @a req (len bytes) to 127.0.0.1:port, read to EOF.  0 on success. */
int http_raw(int port, const char *req, size_t len, http_resp *r);
/* A request with Connection: close. method, path, content type (or NULL),
 * body (or NULL). */
int http_do(int port, const char *method, const char *path, const char *ctype,
            const char *body, http_resp *r);
void http_free(http_resp *r);

typedef struct daemon_proc {
  pid_t pid;
  int port;
  char log_path[64]; /* its stderr */
} daemon_proc;

/* The daemon's stderr so far (malloc'd), or NULL. */
char *daemon_log(const daemon_proc *d);

/* Start the daemon binary with extra args (NULL-terminated); waits for the
 * URL line.  0 on success. */
int daemon_start(const char *bin, const char *const *args, daemon_proc *d);
/* SIGTERM and wait; returns the exit status (or -1). */
int daemon_stop(daemon_proc *d);
/* The same with another signal (SIGINT). */
int daemon_stop_with(daemon_proc *d, int sig);

#endif
