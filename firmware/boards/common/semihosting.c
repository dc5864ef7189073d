/* ARM semihosting calls (semihosting.h). */
#include "semihosting.h"

#include <stdint.h>

#define SYS_OPEN 0x01u
#define SYS_CLOSE 0x02u
#define SYS_WRITE0 0x04u
#define SYS_WRITE 0x05u
#define SYS_READ 0x06u
#define SYS_EXIT_EXTENDED 0x20u
#define ADP_STOPPED_APPLICATION_EXIT 0x20026u

static long semihosting_call(uint32_t operation, const void *argument) {
  register uint32_t r0 __asm__("r0") = operation;
  register const void *r1 __asm__("r1") = argument;
  __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return (long)(int32_t)r0;
}

void semihosting_exit(int code) {
  const uint32_t block[2] = {ADP_STOPPED_APPLICATION_EXIT, (uint32_t)code};
  semihosting_call(SYS_EXIT_EXTENDED, block);
  for (;;) {
  }
}

static size_t text_length(const char *text) {
  size_t length = 0u;
  while (text[length] != '\0') {
    length++;
  }
  return length;
}

int semihosting_open(const char *path, semihosting_mode_t mode) {
  const uint32_t block[3] = {(uint32_t)(uintptr_t)path, (uint32_t)mode,
                             (uint32_t)text_length(path)};
  return (int)semihosting_call(SYS_OPEN, block);
}

int semihosting_close(int handle) {
  const uint32_t block[1] = {(uint32_t)handle};
  return (int)semihosting_call(SYS_CLOSE, block);
}

/* SYS_READ answers the number of bytes NOT read. */
long semihosting_read(int handle, void *data, size_t length) {
  const uint32_t block[3] = {(uint32_t)handle, (uint32_t)(uintptr_t)data, (uint32_t)length};
  const long left = semihosting_call(SYS_READ, block);
  return left < 0 || (size_t)left > length ? -1 : (long)length - left;
}

int semihosting_write(int handle, const void *data, size_t length) {
  const uint32_t block[3] = {(uint32_t)handle, (uint32_t)(uintptr_t)data, (uint32_t)length};
  return semihosting_call(SYS_WRITE, block) == 0 ? 0 : -1;
}

void semihosting_write_text(const char *text) { semihosting_call(SYS_WRITE0, text); }
