/* ARM semihosting: the QEMU host's files and exit status seen from the firmware
 * (`-semihosting-config enable=on,target=native`). Every call is a `bkpt 0xAB`, which
 * traps to the debugger: without QEMU or a debugger attached, it faults. */
#ifndef FIRMWARE_BOARDS_COMMON_SEMIHOSTING_H
#define FIRMWARE_BOARDS_COMMON_SEMIHOSTING_H

#include <stddef.h>

typedef enum {
  SEMIHOSTING_READ = 0,   /* "rb" */
  SEMIHOSTING_WRITE = 4,  /* "wb": created or truncated */
} semihosting_mode_t;

/* Ends the run: QEMU exits with `code` (SYS_EXIT_EXTENDED). */
__attribute__((noreturn)) void semihosting_exit(int code);

/* Opens a host file, relative to QEMU's working directory; a handle, or -1. */
int semihosting_open(const char *path, semihosting_mode_t mode);

int semihosting_close(int handle);

/* Reads up to `length` bytes; returns the number read (0 at the end of the file), or -1. */
long semihosting_read(int handle, void *data, size_t length);

/* Writes `length` bytes; 0 when all were written, -1 otherwise. */
int semihosting_write(int handle, const void *data, size_t length);

/* Writes a NUL-terminated text to QEMU's standard output (the debug console). */
void semihosting_write_text(const char *text);

#endif /* FIRMWARE_BOARDS_COMMON_SEMIHOSTING_H */
