// Minimal Cortex-M4 start-up for QEMU: vector table, FPU on, .data/.bss set up, main, semihosting exit.
#include <stdint.h>

int main(void);
void reset_handler(void);
extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _stack_top;

// Returns the semihosting result of operation op with argument block arg (BKPT 0xAB on M-profile).
static int semihost(int op, const void *arg)
{
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

// Returns nothing; writes the zero-terminated string s to the host console (SYS_WRITE0).
void semihost_write0(const char *s)
{
    semihost(0x04, s);
}

// Does not return; ends the emulation with the exit code (SYS_EXIT_EXTENDED, ADP_Stopped_ApplicationExit).
void semihost_exit(int code)
{
    uint32_t block[2] = {0x20026, (uint32_t)code};
    semihost(0x20, block);
    for (;;) {
    }
}

// Does not return; any fault ends the emulation with exit code 3.
static void fault_handler(void)
{
    semihost_exit(3);
}

// Does not return; the reset entry point.
void reset_handler(void)
{
    uint32_t *src = &_sidata, *dst;
    *(volatile uint32_t *)0xE000ED88 |= 0xFu << 20;  // CPACR: full access to CP10/CP11 (the FPU)
    __asm__ volatile("dsb\n\tisb");
    for (dst = &_sdata; dst < &_edata;)
        *dst++ = *src++;
    for (dst = &_sbss; dst < &_ebss;)
        *dst++ = 0;
    semihost_exit(main());
}

__attribute__((section(".vectors"), used)) static const void *const vectors[16] = {
    &_stack_top, (const void *)reset_handler, (const void *)fault_handler, (const void *)fault_handler,
    (const void *)fault_handler, (const void *)fault_handler, (const void *)fault_handler,
};
