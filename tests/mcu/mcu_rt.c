/*
 * mcu_rt.c - the bare-metal run time of the MCU tests: vector table, reset, semihosting output
 * and exit (QEMU -semihosting returns the exit code), stack painting for the high-water mark.
 * No newlib start-up files and no heap: the core needs none.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "mcu_rt.h"

extern uint32_t __data_start, __data_end, __data_load, __bss_start, __bss_end, __stack_limit, __stack_top;
extern int main(void);
void mcu_reset(void);
void mcu_fault(void);

__attribute__((section(".isr_vector"), used)) static const void *const vectors[16] = {
    &__stack_top, (const void *)mcu_reset, (const void *)mcu_fault, (const void *)mcu_fault,
    (const void *)mcu_fault, (const void *)mcu_fault, (const void *)mcu_fault,
};

/* ARM semihosting call (bkpt 0xab in Thumb state): r0 = operation, r1 = argument. */
static int semihost(int op, const void *arg)
{
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void mcu_puts(const char *s)
{
    semihost(0x04, s); /* SYS_WRITE0 */
}

void mcu_put_int(long long v)
{
    char buf[24];
    int i = 23;
    buf[i] = '\0';
    const int neg = v < 0;
    unsigned long long u = neg ? (unsigned long long)(-(v + 1)) + 1u : (unsigned long long)v;
    do {
        buf[--i] = (char)('0' + (int)(u % 10u));
        u /= 10u;
    } while (u != 0u && i > 1);
    if (neg) {
        buf[--i] = '-';
    }
    mcu_puts(&buf[i]);
}

void mcu_put_fixed(float v, int decimals)
{
    if (isnan(v)) {
        mcu_puts("nan");
        return;
    }
    long long scale = 1;
    for (int i = 0; i < decimals; i++) {
        scale *= 10;
    }
    const float a = v < 0.0f ? -v : v;
    if (a > 9.0e15f / (float)scale) {
        mcu_puts(v < 0.0f ? "-big" : "big");
        return;
    }
    const long long n = (long long)(a * (float)scale + 0.5f);
    if (v < 0.0f) {
        mcu_puts("-");
    }
    mcu_put_int(n / scale);
    if (decimals > 0) {
        char frac[20];
        long long f = n % scale;
        for (int i = decimals - 1; i >= 0; i--) {
            frac[i] = (char)('0' + (int)(f % 10));
            f /= 10;
        }
        frac[decimals] = '\0';
        mcu_puts(".");
        mcu_puts(frac);
    }
}

void mcu_exit(int code)
{
    /* SYS_EXIT_EXTENDED: ADS_Stopped_ApplicationExit with the exit code */
    const uint32_t block[2] = {0x20026u, (uint32_t)code};
    semihost(0x20, block);
    for (;;) {
    }
}

void mcu_fault(void)
{
    mcu_puts("mcu: hard fault\n");
    mcu_exit(3);
}

#define STACK_PAINT 0xa5a5a5a5u

void mcu_stack_paint(void)
{
    uint32_t *p = &__stack_limit;
    uintptr_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    sp -= 256; /* below this frame, with margin */
    while ((uintptr_t)p < sp) {
        *p++ = STACK_PAINT;
    }
}

uint32_t mcu_stack_used(void)
{
    const uint32_t *p = &__stack_limit;
    while (p < &__stack_top && *p == STACK_PAINT) {
        p++;
    }
    return (uint32_t)((uintptr_t)&__stack_top - (uintptr_t)p);
}

void mcu_reset(void)
{
    /* the FPU: full access for CP10 and CP11 before any floating-point instruction */
    volatile uint32_t *cpacr = (volatile uint32_t *)0xE000ED88u;
    *cpacr |= 0xFu << 20;
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    memcpy(&__data_start, &__data_load, (size_t)((uintptr_t)&__data_end - (uintptr_t)&__data_start));
    memset(&__bss_start, 0, (size_t)((uintptr_t)&__bss_end - (uintptr_t)&__bss_start));
    mcu_exit(main());
}
