// Measurements for the bare-metal programs of embedded/ (QEMU mps2-an386): a workspace in the RAM between .bss and
// the stack, the stack a call used (painted before, scanned after), and numbers written to the host console.
#ifndef FS_EMBEDDED_MEASURE_H
#define FS_EMBEDDED_MEASURE_H

#include <stddef.h>
#include <stdint.h>

void semihost_write0(const char *s);
void semihost_exit(int code);

// Returns the 8-byte aligned start of the RAM above .bss that no variable uses, and writes its size [bytes] to bytes.
void *free_ram(size_t *bytes);

// Returns nothing; paints the free stack below the caller's frame, before the call to be measured.
void stack_paint(void);

// Returns the bytes of stack the calls since stack_paint() used, below the frame of stack_paint's caller.
uint32_t stack_used(void);

// Returns nothing; writes " name value" (value in decimal, a minus sign if negative) to the console.
void put_field(const char *name, int32_t value);

#endif
