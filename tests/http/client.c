/*
 * client.c: see client.h.
 */
#define _GNU_SOURCE
#include "client.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

static void header(const char *raw, const char *name, char *out, size_t n) {
  const char *h = raw;
  size_t ln = strlen(name);
  out[0] = 0;
  while ((h = strstr(h, "\r\n")) != NULL) {
    h += 2;
    if (h[0] == '\r')
      return;
    if (strncasecmp(h, name, ln) == 0 && h[ln] == ':') {
      const char *v = h + ln + 1;
      while (*v == ' ')
        v++;
      size_t k = strcspn(v, "\r\n");
      if (k >= n)
        k = n - 1;
      memcpy(out, v, k);
      out[k] = 0;
      return;
    }
  }
}

/* The source address of this thread's connections (NULL: any). */
static _Thread_local const char *source;

void http_set_source(const char *addr) { source = addr; }

int http_connect(int port) {
  struct sockaddr_in a;
  int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0)
    return -1;
  memset(&a, 0, sizeof a);
  a.sin_family = AF_INET;
  if (source) {
    if (inet_pton(AF_INET, source, &a.sin_addr) != 1 ||
        bind(fd, (struct sockaddr *)&a, sizeof a) != 0) {
      close(fd);
      return -1;
    }
  }
  a.sin_port = htons((uint16_t)port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, (struct sockaddr *)&a, sizeof a) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

int http_send(int port, const char *req, size_t len) {
  int fd = http_connect(port);
  if (fd < 0)
    return -1;
  /* send what the server takes; it may close early (413) */
  for (size_t off = 0; off < len;) {
    ssize_t k = send(fd, req + off, len - off, MSG_NOSIGNAL);
    if (k <= 0)
      break;
    off += (size_t)k;
  }
  return fd;
}

/* Decode a chunked body of @a avail bytes in place (it only shrinks), binary
 * safe; its length into *len; -1 when malformed. */
static int dechunk(char *body, size_t avail, size_t *len) {
  char *in = body, *out = body, *stop = body + avail;
  for (;;) {
    char *end;
    unsigned long n = strtoul(in, &end, 16);
    if (end == in || !(end = strstr(end, "\r\n")))
      return -1;
    in = end + 2;
    if (n == 0)
      break;
    if ((size_t)(stop - in) < n + 2)
      return -1;
    memmove(out, in, n);
    out += n;
    in += n + 2;
  }
  *out = 0;
  *len = (size_t)(out - body);
  return 0;
}

int http_read(int fd, int timeout_ms, http_resp *r) {
  memset(r, 0, sizeof *r);
  size_t cap = 65536, n = 0;
  char *buf = malloc(cap);
  for (;;) {
    struct pollfd p = {fd, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) <= 0)
      break;
    if (n + 4096 > cap) {
      cap *= 2;
      buf = realloc(buf, cap);
    }
    ssize_t k = recv(fd, buf + n, cap - n - 1, 0);
    if (k <= 0) {
      r->eof = 1; /* closed or reset by the server */
      break;
    }
    n += (size_t)k;
  }
  close(fd);
  buf[n] = 0;
  r->raw = buf;
  if (n < 12 || strncmp(buf, "HTTP/1.", 7) != 0)
    return n ? -2 : -3;
  r->status = atoi(buf + 9);
  char *b = strstr(buf, "\r\n\r\n");
  r->body = b ? b + 4 : buf + n;
  r->len = (size_t)(buf + n - r->body);
  header(buf, "Content-Type", r->ctype, sizeof r->ctype);
  header(buf, "Retry-After", r->retry_after, sizeof r->retry_after);
  header(buf, "Allow", r->allow, sizeof r->allow);
  char te[32];
  header(buf, "Transfer-Encoding", te, sizeof te);
  if (strcmp(te, "chunked") == 0) {
    r->chunked = 1;
    if (dechunk(r->body, r->len, &r->len))
      return -2;
  }
  return 0;
}

int http_raw(int port, const char *req, size_t len, http_resp *r) {
  memset(r, 0, sizeof *r);
  int fd = http_send(port, req, len);
  if (fd < 0)
    return -1;
  return http_read(fd, 60000, r);
}

/* The text of a request with Connection: close (malloc'd). */
char *http_request(const char *method, const char *path, const char *ctype,
                   const char *body, size_t *len) {
  size_t bl = body ? strlen(body) : 0;
  size_t cap = bl + 512;
  char *req = malloc(cap);
  int h = snprintf(req, cap,
                   "%s %s HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n"
                   "%s%s%s",
                   method, path, ctype ? "Content-Type: " : "",
                   ctype ? ctype : "", ctype ? "\r\n" : "");
  if (body)
    h += snprintf(req + h, cap - (size_t)h, "Content-Length: %zu\r\n", bl);
  h += snprintf(req + h, cap - (size_t)h, "\r\n");
  if (body)
    memcpy(req + h, body, bl);
  *len = (size_t)h + bl;
  return req;
}

int http_do(int port, const char *method, const char *path, const char *ctype,
            const char *body, http_resp *r) {
  size_t len;
  char *req = http_request(method, path, ctype, body, &len);
  int rc = http_raw(port, req, len, r);
  free(req);
  return rc;
}

void http_free(http_resp *r) {
  free(r->raw);
  memset(r, 0, sizeof *r);
}

int daemon_start(const char *bin, const char *const *args, daemon_proc *d) {
  const char *argv[32];
  int n = 0;
  argv[n++] = bin;
  argv[n++] = "--port";
  argv[n++] = "0";
  for (int i = 0; args && args[i] && n < 30; i++)
    argv[n++] = args[i];
  argv[n] = NULL;
  /* its stderr goes to a file, so a chatty access log never blocks it */
  snprintf(d->log_path, sizeof d->log_path, "/tmp/stickslipd-test-XXXXXX");
  int fd = mkstemp(d->log_path);
  if (fd < 0)
    return -1;
  d->pid = fork();
  if (d->pid < 0)
    return -1;
  if (d->pid == 0) {
    dup2(fd, 2);
    close(fd);
    execv(bin, (char *const *)argv);
    _exit(127);
  }
  close(fd);
  for (int tries = 0; tries < 2000; tries++) {
    char *log = daemon_log(d);
    char *u = log ? strstr(log, "http://127.0.0.1:") : NULL;
    if (u) {
      d->port = atoi(u + strlen("http://127.0.0.1:"));
      free(log);
      return 0;
    }
    free(log);
    int st;
    if (waitpid(d->pid, &st, WNOHANG) == d->pid)
      return -1;
    usleep(10000);
  }
  return -1;
}

char *daemon_log(const daemon_proc *d) {
  FILE *f = fopen(d->log_path, "rb");
  if (!f)
    return NULL;
  size_t cap = 1 << 16, n = 0;
  char *b = malloc(cap);
  size_t k;
  while ((k = fread(b + n, 1, cap - n - 1, f)) > 0) {
    n += k;
    if (n + 1 >= cap)
      b = realloc(b, cap *= 2);
  }
  b[n] = 0;
  fclose(f);
  return b;
}

int daemon_stop(daemon_proc *d) { return daemon_stop_with(d, SIGTERM); }

int daemon_stop_with(daemon_proc *d, int sig) {
  int st;
  kill(d->pid, sig);
  if (waitpid(d->pid, &st, 0) != d->pid)
    return -1;
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}
