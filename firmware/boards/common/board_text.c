/* Number formatting (board_text.h). */
#include "board_text.h"

#include <string.h>

size_t board_text_u32(uint32_t value, char text[BOARD_TEXT_U32_MAX]) {
  char reversed[BOARD_TEXT_U32_MAX];
  size_t length = 0u;
  do {
    reversed[length++] = (char)('0' + value % 10u);
    value /= 10u;
  } while (value != 0u);
  for (size_t i = 0u; i < length; i++) {
    text[i] = reversed[length - 1u - i];
  }
  text[length] = '\0';
  return length;
}

void board_text_hex32(uint32_t value, char text[9]) {
  static const char digits[] = "0123456789abcdef";
  for (unsigned i = 0u; i < 8u; i++) {
    text[i] = digits[(value >> (28u - 4u * i)) & 0xFu];
  }
  text[8] = '\0';
}

void board_text_float_bits(float value, char text[9]) {
  uint32_t bits;
  memcpy(&bits, &value, sizeof bits);
  board_text_hex32(bits, text);
}
