/* Pseudo-terminal ping-pong: the round trip of a lock-step SITL sample without
 * its compute (docs/monte-carlo.md, "The lock-step round trip").
 * One thread writes 40 bytes to pty A's master, the other reads them on A's
 * slave and answers 16 bytes on pty B's slave, read back on B's master.
 *
 *   gcc -O2 -o /tmp/pty_pingpong tools/pty_pingpong.c -lpthread
 *   /tmp/pty_pingpong MODES [SPIN_US [CPU]]
 *
 * MODES: two letters, the waiting of the writer's side then of the answering
 * side: B blocks in poll, Y polls with sched_yield, S spins SPIN_US then
 * blocks, T polls with sched_yield SPIN_US then blocks. CPU: pin both threads
 * to that core. Prints the mean round trip (µs) of 4000. */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <unistd.h>
#include <pthread.h>
#include <poll.h>
#include <termios.h>
#include <time.h>
#include <sched.h>
#include <errno.h>
static double now(){struct timespec t;clock_gettime(CLOCK_MONOTONIC,&t);return t.tv_sec+t.tv_nsec*1e-9;}
int m1,s1,m2,s2; int N=4000; char ma,mb; double spin_s=50e-6; int pin=-1;
static void openpty_(int*m,int*s){*m=posix_openpt(O_RDWR|O_NOCTTY);grantpt(*m);unlockpt(*m);*s=open(ptsname(*m),O_RDWR|O_NOCTTY);struct termios t;tcgetattr(*s,&t);cfmakeraw(&t);tcsetattr(*s,TCSANOW,&t);fcntl(*s,F_SETFL,O_NONBLOCK);fcntl(*m,F_SETFL,O_NONBLOCK);}
static void rd(int fd,char*b,int n,char mode){int got=0;double t0=now();while(got<n){int r=read(fd,b,n-got); if(r>0){got+=r;continue;}
 if(mode=='Y'){sched_yield();} else if(mode=='S'||mode=='T'){ if(now()-t0>spin_s){struct pollfd p={fd,POLLIN,0};poll(&p,1,-1);} else if(mode=='T') sched_yield(); else __builtin_ia32_pause(); } else {struct pollfd p={fd,POLLIN,0};poll(&p,1,-1);}}}
static void pinme(int c){if(c<0)return;cpu_set_t s;CPU_ZERO(&s);CPU_SET(c,&s);sched_setaffinity(0,sizeof s,&s);}
void* other(void*a){pinme(pin);char b[64];for(int i=0;i<N;i++){rd(s1,b,40,mb);write(s2,b,16);}return 0;}
int main(int c,char**v){ma=v[1][0];mb=v[1][1];if(c>2)spin_s=atof(v[2])*1e-6;if(c>3)pin=atoi(v[3]);openpty_(&m1,&s1);openpty_(&m2,&s2);
 pinme(pin);pthread_t t;pthread_create(&t,0,other,0);char b[64]={0};double t0=now();
 for(int i=0;i<N;i++){write(m1,b,40);rd(m2,b,16,ma);} double dt=now()-t0;pthread_join(t,0);
 printf("%.1f\n",dt/N*1e6);return 0;}
