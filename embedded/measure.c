// Measurements for the bare-metal programs of embedded/: see measure.h.
#include "measure.h"

extern uint32_t _ebss, _stack_top;

enum { STACK_RESERVE = 64 * 1024 };  // bytes below _stack_top kept for the stack
#define PAINT 0x5AA5C33Cu

static uintptr_t caller_sp;  // the stack pointer of stack_paint's caller

void *free_ram(size_t *bytes)
{
    uintptr_t start = ((uintptr_t)&_ebss + 7) & ~(uintptr_t)7;
    *bytes = (uintptr_t)&_stack_top - STACK_RESERVE - start;
    return (void *)start;
}

// Paints below this function's own stack pointer (a leaf without interrupts: nothing else lives there), which is the
// caller's stack pointer less this frame's few bytes.
__attribute__((noinline)) void stack_paint(void)
{
    volatile uint32_t *w = (volatile uint32_t *)((uintptr_t)&_stack_top - STACK_RESERVE);
    uintptr_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    caller_sp = sp;
    while ((uintptr_t)w < sp)
        *w++ = PAINT;
}

__attribute__((noinline)) uint32_t stack_used(void)
{
    const volatile uint32_t *w = (const volatile uint32_t *)((uintptr_t)&_stack_top - STACK_RESERVE);
    while ((uintptr_t)w < caller_sp && *w == PAINT)
        w++;
    return (uint32_t)(caller_sp - (uintptr_t)w);
}

void put_field(const char *name, int32_t value)
{
    char buf[14];
    uint32_t u = value < 0 ? 0u - (uint32_t)value : (uint32_t)value;
    int k = 13;
    buf[13] = 0;
    do {
        buf[--k] = (char)('0' + u % 10);
        u /= 10;
    } while (u && k > 1);
    if (value < 0)
        buf[--k] = '-';
    buf[--k] = ' ';
    semihost_write0(" ");
    semihost_write0(name);
    semihost_write0(buf + k);
}
