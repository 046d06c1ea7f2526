#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
typedef double v4 __attribute__((vector_size(32)));
void dgemm_(const char*,const char*,const int*,const int*,const int*,const double*,const double*,const int*,const double*,const int*,const double*,double*,const int*);
static double now(){struct timespec t;clock_gettime(CLOCK_MONOTONIC,&t);return t.tv_sec+1e-9*t.tv_nsec;}
/* x (m x 2) += alpha A c, A m x k */
__attribute__((target("avx2,fma"))) static void nn(int m,int k,const double*A,int lda,const double*c,int ldc,double alpha,double*x0,double*x1,double*t){
  int m4=m-m%4;
  memset(t,0,sizeof(double)*2*m);
  for(int j=0;j<k;j+=4){ int nj=k-j<4?k-j:4; const double*ac[4]; double c0[4],c1[4];
    for(int q=0;q<4;q++){int jj=j+(q<nj?q:nj-1); ac[q]=A+(long)jj*lda; c0[q]=q<nj?c[jj]:0; c1[q]=q<nj?c[ldc+jj]:0;}
    v4 a0={c0[0],c0[0],c0[0],c0[0]},a1={c0[1],c0[1],c0[1],c0[1]},a2={c0[2],c0[2],c0[2],c0[2]},a3={c0[3],c0[3],c0[3],c0[3]};
    v4 b0={c1[0],c1[0],c1[0],c1[0]},b1={c1[1],c1[1],c1[1],c1[1]},b2={c1[2],c1[2],c1[2],c1[2]},b3={c1[3],c1[3],c1[3],c1[3]};
    for(int i=0;i<m4;i+=4){ v4 u0,u1,u2,u3,s0,s1; memcpy(&u0,ac[0]+i,32);memcpy(&u1,ac[1]+i,32);memcpy(&u2,ac[2]+i,32);memcpy(&u3,ac[3]+i,32);
      memcpy(&s0,t+i,32); memcpy(&s1,t+m+i,32);
      s0+=u0*a0+u1*a1+u2*a2+u3*a3; s1+=u0*b0+u1*b1+u2*b2+u3*b3;
      memcpy(t+i,&s0,32); memcpy(t+m+i,&s1,32);}
    for(int i=m4;i<m;i++){ for(int q=0;q<4;q++){t[i]+=ac[q][i]*c0[q]; t[m+i]+=ac[q][i]*c1[q];}}
  }
  for(int i=0;i<m;i++){x0[i]+=alpha*t[i]; x1[i]+=alpha*t[m+i];}
}
int main(int argc,char**argv){
  int n=200000,k=60,p=2,R=atoi(argv[1]); double one=1,mone=-1;
  double *V=malloc(sizeof(double)*n*k),*w=malloc(sizeof(double)*n*p),*w2=malloc(sizeof(double)*n*p),c[200],*t=malloc(sizeof(double)*2*R);
  for(long i=0;i<(long)n*k;i++)V[i]=1.0/(i%97+1); for(long i=0;i<(long)n*p;i++)w2[i]=w[i]=1.0/(i%89+1); for(int i=0;i<200;i++)c[i]=1e-3*(i%7);
  for(int rep=0;rep<3;rep++){ int reps=10; double t0=now();
  for(int r=0;r<reps;r++) for(int i0=0;i0<n;i0+=R){int bm=n-i0<R?n-i0:R; dgemm_("N","N",&bm,&p,&k,&mone,V+i0,&n,c,&k,&one,w+i0,&n);}
  double t1=now();
  for(int r=0;r<reps;r++) for(int i0=0;i0<n;i0+=R){int bm=n-i0<R?n-i0:R; nn(bm,k,V+i0,n,c,k,-1.0,w2+i0,w2+n+i0,t);}
  double t2=now(); double gb=(double)n*k*8*reps/1e9; double d=0; for(long i=0;i<2L*n;i++){double e=w[i]-w2[i]; if(e<0)e=-e; if(e>d)d=e;}
  printf("BLAS NN %.1f ms (%.1f GB/s)  own %.1f ms (%.1f GB/s) maxdiff %g\n",(t1-t0)/reps*1e3,gb/(t1-t0),(t2-t1)/reps*1e3,gb/(t2-t1),d);}
}
