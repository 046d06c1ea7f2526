#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
void dgemm_(const char*,const char*,const int*,const int*,const int*,const double*,const double*,const int*,const double*,const int*,const double*,double*,const int*);
static double now(){struct timespec t;clock_gettime(CLOCK_MONOTONIC,&t);return t.tv_sec+1e-9*t.tv_nsec;}
int main(int argc,char**argv){
  int n=200000,k=60,p=2,R=atoi(argv[1]); double one=1,mone=-1;
  double *V=malloc(sizeof(double)*n*k),*w=malloc(sizeof(double)*n*p),c[200];
  for(long i=0;i<(long)n*k;i++)V[i]=1.0/(i%97+1); for(long i=0;i<(long)n*p;i++)w[i]=1.0/(i%89+1);
  for(int rep=0;rep<3;rep++){
  double t0=now(); int reps=10;
  for(int r=0;r<reps;r++){ memset(c,0,sizeof c);
    for(int i0=0;i0<n;i0+=R){int bm=n-i0<R?n-i0:R; dgemm_("T","N",&k,&p,&bm,&one,V+i0,&n,w+i0,&n,&one,c,&k);} }
  double t1=now();
  for(int r=0;r<reps;r++){
    for(int i0=0;i0<n;i0+=R){int bm=n-i0<R?n-i0:R; dgemm_("N","N",&bm,&p,&k,&mone,V+i0,&n,c,&k,&one,w+i0,&n);} }
  double t2=now();
  double s=0; for(int r=0;r<reps;r++){ double s0=0,s1=0,s2=0,s3=0; for(long i=0;i<(long)n*k;i+=4){s0+=V[i];s1+=V[i+1];s2+=V[i+2];s3+=V[i+3];} s+=s0+s1+s2+s3;}
  double t3=now();
  /* hand-written: per row chunk, c += V^T w for 2 columns, plain loops */
  for(int r=0;r<reps;r++){ memset(c,0,sizeof c);
    for(int i0=0;i0<n;i0+=R){int bm=n-i0<R?n-i0:R; for(int j=0;j<k;j++){const double*v=V+(long)j*n+i0; double a0=0,a1=0,b0=0,b1=0; for(int i=0;i<bm;i+=2){a0+=v[i]*w[i0+i];a1+=v[i+1]*w[i0+i+1];b0+=v[i]*w[n+i0+i];b1+=v[i+1]*w[n+i0+i+1];} c[j]+=a0+a1; c[k+j]+=b0+b1;}}}
  double t4=now();
  double gb=(double)n*k*8*reps/1e9;
  printf("TN %.1f ms (%.1f GB/s)  NN %.1f ms (%.1f GB/s)  read %.1f ms (%.1f GB/s) hand TN %.1f ms (%.1f GB/s) %g\n",(t1-t0)/reps*1e3,gb/(t1-t0),(t2-t1)/reps*1e3,gb/(t2-t1),(t3-t2)/reps*1e3,gb/(t3-t2),(t4-t3)/reps*1e3,gb/(t4-t3),s+c[0]);
  }
}
