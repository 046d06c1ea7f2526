#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
typedef double v4 __attribute__((vector_size(32)));
static double now(){struct timespec t;clock_gettime(CLOCK_MONOTONIC,&t);return t.tv_sec+1e-9*t.tv_nsec;}
static inline v4 ld(const double*p){v4 v; memcpy(&v,p,32); return v;}
static double hs(v4 v){return (v[0]+v[1])+(v[2]+v[3]);}
/* c (k x 2) += V^T w over rows [0,n): 4 columns at a time, rows 4 wide */
static void tn4(int n,int k,const double*V,int ldv,const double*w0,const double*w1,double*c){
  int j=0;
  for(;j+4<=k;j+=4){const double*a=V+(long)j*ldv,*b=a+ldv,*cc=b+ldv,*d=cc+ldv;
    v4 s00={0},s01={0},s10={0},s11={0},s20={0},s21={0},s30={0},s31={0};
    for(int i=0;i<n;i+=4){v4 x0=ld(w0+i),x1=ld(w1+i),va=ld(a+i),vb=ld(b+i),vc=ld(cc+i),vd=ld(d+i);
      s00+=va*x0;s01+=va*x1;s10+=vb*x0;s11+=vb*x1;s20+=vc*x0;s21+=vc*x1;s30+=vd*x0;s31+=vd*x1;}
    c[j]+=hs(s00);c[k+j]+=hs(s01);c[j+1]+=hs(s10);c[k+j+1]+=hs(s11);c[j+2]+=hs(s20);c[k+j+2]+=hs(s21);c[j+3]+=hs(s30);c[k+j+3]+=hs(s31);}
  for(;j<k;j++){const double*a=V+(long)j*ldv; v4 s0={0},s1={0}; for(int i=0;i<n;i+=4){v4 va=ld(a+i);s0+=va*ld(w0+i);s1+=va*ld(w1+i);} c[j]+=hs(s0);c[k+j]+=hs(s1);}
}
int main(int argc,char**argv){
  int n=200000,k=60,R=atoi(argv[1]);
  double *V=malloc(sizeof(double)*n*k),*w=malloc(sizeof(double)*n*2),c[200];
  for(long i=0;i<(long)n*k;i++)V[i]=1.0/(i%97+1); for(long i=0;i<(long)n*2;i++)w[i]=1.0/(i%89+1);
  for(int rep=0;rep<3;rep++){ int reps=10; double t0=now();
  for(int r=0;r<reps;r++){ memset(c,0,sizeof c); for(int i0=0;i0<n;i0+=R){int bm=n-i0<R?n-i0:R; tn4(bm,k,V+i0,n,w+i0,w+n+i0,c);} }
  double t1=now(); double gb=(double)n*k*8*reps/1e9;
  printf("R=%d tn4 %.1f ms (%.1f GB/s) %g\n",R,(t1-t0)/reps*1e3,gb/(t1-t0),c[3]);}
}
