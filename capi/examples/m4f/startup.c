/* Start-up of the C example on QEMU mps2-an386: the vector table, the reset handler (copies
 * .data, zeroes .bss, enables the FPU, opens semihosting, calls main, exits with its code) and a
 * HardFault handler that exits with a failure code instead of hanging. */
#include <stdint.h>
#include <stdlib.h>

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
extern int main(void);
extern void initialise_monitor_handles(void);
void SysTick_Handler(void);

void Reset_Handler(void) {
    uint32_t *src = &_sidata, *dst = &_sdata;
    while (dst < &_edata) *dst++ = *src++;
    for (dst = &_sbss; dst < &_ebss;) *dst++ = 0;
    /* CPACR: full access to CP10 and CP11 (the FPU), before any float instruction. */
    *(volatile uint32_t *)0xE000ED88 |= 0xFu << 20;
    __asm volatile("dsb\n isb" ::: "memory");
    initialise_monitor_handles();
    exit(main());
}

/* Semihosting SYS_EXIT with ADP_Stopped_RunTimeError: QEMU exits with code 1. */
static void fault(void) {
    __asm volatile("mov r0, #0x18\n"
                   "ldr r1, =0x20023\n"
                   "bkpt 0xab\n" ::: "r0", "r1", "memory");
    for (;;) {
    }
}

void HardFault_Handler(void) { fault(); }
void Default_Handler(void) { fault(); }

__attribute__((section(".vectors"), used)) static void (*const vectors[16])(void) = {
    (void (*)(void))(&_estack), Reset_Handler, Default_Handler, HardFault_Handler,
    Default_Handler, Default_Handler, Default_Handler, 0, 0, 0, 0, Default_Handler,
    Default_Handler, 0, Default_Handler, SysTick_Handler,
};

/* newlib's exit() runs __libc_fini_array, which calls _fini (crti.o, left out with
 * -nostartfiles): nothing to do here. */
void _init(void) {}
void _fini(void) {}
