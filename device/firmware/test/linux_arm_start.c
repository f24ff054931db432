/* Lets test/tick_bench.c, built for the Cortex-M0+, run under qemu-arm (Linux user mode):
 * a start routine and write/exit through Linux system calls (Thumb code of the M0+ runs
 * unchanged on the emulated core). Used by `make isr-cost-arm`. */
int main(void);

static int syscall3(int n, int a, int b, int c)
{
    register int r0 __asm("r0") = a;
    register int r1 __asm("r1") = b;
    register int r2 __asm("r2") = c;
    register int r7 __asm("r7") = n;
    __asm volatile("svc 0" : "+r"(r0) : "r"(r1), "r"(r2), "r"(r7) : "memory");
    return r0;
}

int _write(int fd, const char *p, int n) { return syscall3(4, fd, (int)p, n); }

void _exit(int code)
{
    for (;;)
        syscall3(1, code, 0, 0);
}

void _start(void) { _exit(main()); }
