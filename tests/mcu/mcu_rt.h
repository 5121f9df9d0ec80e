/* mcu_rt.h - bare-metal run time of the MCU tests (semihosting output and exit, stack painting). */
#ifndef MCU_RT_H
#define MCU_RT_H

#include <stdint.h>

void mcu_puts(const char *s);
void mcu_put_int(long long v);
void mcu_put_fixed(float v, int decimals);
void mcu_exit(int code) __attribute__((noreturn));
/* Fills the unused stack below the caller with a pattern; mcu_stack_used() then gives the deepest
 * stack reached since (bytes from the top), a measured high-water mark. */
void mcu_stack_paint(void);
uint32_t mcu_stack_used(void);

#endif
