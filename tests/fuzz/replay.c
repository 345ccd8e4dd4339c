/*
 * replay.c: run the fuzz target over every file of a corpus directory, so
 * that the stored corpus is a test on any compiler.  Usage: replay DIR
 */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int main(int argc, char **argv) {
  if (argc < 2)
    return 2;
  DIR *d = opendir(argv[1]);
  struct dirent *e;
  int n = 0;
  if (!d) {
    perror(argv[1]);
    return 2;
  }
  while ((e = readdir(d)) != NULL) {
    char path[4096];
    if (e->d_name[0] == '.')
      continue;
    snprintf(path, sizeof path, "%s/%s", argv[1], e->d_name);
    FILE *f = fopen(path, "rb");
    if (!f)
      continue;
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *buf = malloc((size_t)len + 1);
    if (fread(buf, 1, (size_t)len, f) != (size_t)len) {
      fclose(f);
      free(buf);
      continue;
    }
    fclose(f);
    LLVMFuzzerTestOneInput(buf, (size_t)len);
    free(buf);
    n++;
  }
  closedir(d);
  printf("%d inputs replayed, 0 failures\n", n);
  return n > 0 ? 0 : 1;
}
