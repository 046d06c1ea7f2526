#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>
#include <stdint.h>
static double cpu(void){struct timespec t;clock_gettime(CLOCK_PROCESS_CPUTIME_ID,&t);return t.tv_sec+1e-9*t.tv_nsec;}
int main(int argc,char**argv){
  int huge=atoi(argv[1]); size_t bytes=(size_t)atol(argv[2])<<20; int reps=atoi(argv[3]);
  double c0=cpu();
  for(int r=0;r<reps;r++){
  double *a=malloc(bytes);
  if(huge){uintptr_t s=((uintptr_t)a+(1<<21)-1)&~(uintptr_t)((1<<21)-1), e=((uintptr_t)a+bytes)&~(uintptr_t)((1<<21)-1); if(e>s) madvise((void*)s,e-s,MADV_HUGEPAGE);}
  memset(a,1,bytes); __asm__ volatile("" :: "r"(a) : "memory"); free(a);}
  double c1=cpu();
  printf("huge %d: %d x %zu MB alloc+touch+free %.3f s per GB\n",huge,reps,bytes>>20,(c1-c0)/(reps*bytes/1e9));
  return 0;}
