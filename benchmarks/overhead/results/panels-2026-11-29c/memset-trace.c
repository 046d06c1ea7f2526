/* Diagnostic only (not a benchmark): logs every memset over 2 MB with its backtrace to stderr.
   gcc -O2 -fPIC -shared -fno-builtin -o ms.so memset-trace.c; LD_PRELOAD=./ms.so build/kryflex reduce ... 2>&1 | grep MEMSET
   Its own memset is a byte loop: timings taken under it mean nothing. */
#define _GNU_SOURCE
#include <string.h>
#include <execinfo.h>
#include <stdio.h>
#include <unistd.h>
void *memset(void *s, int c, size_t n)
{
  if (n > (1 << 21)) {
    void *bt[12]; int k = backtrace(bt, 12);
    char **sy = backtrace_symbols(bt, k);
    fprintf(stderr, "MEMSET %zu:", n);
    for (int i = 1; i < k; i++) fprintf(stderr, " < %s", sy[i]);
    fprintf(stderr, "\n");
  }
  unsigned char *p = s; for (size_t i = 0; i < n; i++) p[i] = (unsigned char)c;
  return s;
}
