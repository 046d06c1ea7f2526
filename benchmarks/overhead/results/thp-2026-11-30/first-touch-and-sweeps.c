#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>
#include <stdint.h>
static double now(void){struct timespec t;clock_gettime(CLOCK_MONOTONIC,&t);return t.tv_sec+1e-9*t.tv_nsec;}
static double cpu(void){struct timespec t;clock_gettime(CLOCK_PROCESS_CPUTIME_ID,&t);return t.tv_sec+1e-9*t.tv_nsec;}
int main(int argc,char**argv){
  int huge=atoi(argv[1]); size_t n=200000, m=60; size_t bytes=n*m*8;
  double c0=cpu();
  double *a=malloc(bytes);
  if(huge){uintptr_t s=((uintptr_t)a+(1<<21)-1)&~(uintptr_t)((1<<21)-1), e=((uintptr_t)a+bytes)&~(uintptr_t)((1<<21)-1); if(e>s) madvise((void*)s,e-s,MADV_HUGEPAGE);}
  memset(a,0,bytes);
  double c1=cpu();
  for(size_t j=0;j<m;j++) for(size_t i=0;i<n;i++) a[i+j*n]=1.0/(i+j+1);
  double c2=cpu(); double s=0;
  /* V^T w with a 2-column w, chunked 2048 rows: like the skinny products */
  double w[2*2048]; for(int i=0;i<4096;i++) w[i]=1.0/(i+1);
  for(int rep=0;rep<20;rep++) for(size_t i0=0;i0<n;i0+=2048){size_t b=n-i0<2048?n-i0:2048; for(size_t j=0;j<m;j++){const double*c=a+j*n+i0; double t0=0,t1=0; for(size_t i=0;i<b;i++){t0+=c[i]*w[i];t1+=c[i]*w[2048+i];} s+=t0+t1;}}
  double c3=cpu();
  printf("huge %d: alloc+zero %.3f s, write %.3f s, 20 sweeps %.3f s (%g)\n",huge,c1-c0,c2-c1,c3-c2,s);
  FILE*f=fopen("/proc/self/smaps_rollup","r"); char l[256]; while(fgets(l,256,f)) if(strstr(l,"AnonHuge")) fputs(l,stdout);
  return 0;}
