/* Number formatting for the boards' text output, without printf: decimal and
 * hexadecimal integers (floats go out as the hex of their IEEE 754 bits: exact). */
#ifndef FIRMWARE_BOARDS_COMMON_BOARD_TEXT_H
#define FIRMWARE_BOARDS_COMMON_BOARD_TEXT_H

#include <stddef.h>
#include <stdint.h>

#define BOARD_TEXT_U32_MAX 11u /* bytes: 10 decimal digits and the NUL */

/* `value` in decimal into `text` (NUL-terminated); returns the length. */
size_t board_text_u32(uint32_t value, char text[BOARD_TEXT_U32_MAX]);

/* `value` as 8 hexadecimal digits (lower case) into `text`, NUL-terminated. */
void board_text_hex32(uint32_t value, char text[9]);

/* The bits of `value` as 8 hexadecimal digits, NUL-terminated. */
void board_text_float_bits(float value, char text[9]);

#endif /* FIRMWARE_BOARDS_COMMON_BOARD_TEXT_H */
