/* The magnetometer probe: the LSM303DLHC driver through the real (emulated) I2C master,
 * driven line by line over UART0 by a test (firmware/tests/qemu/test_qemu_magnetometer.py):
 *   r       read once; answers `mag STATUS CX CY CZ UX UY UZ` (status: the driver's
 *           lsm303dlhc_mag_status_t; counts in decimal, sensor x y z; uT as the hex of
 *           the float's bits, exact)
 *   a HH    use 7-bit address HH (hex) from now on; answers `ok`
 *   g N     use range code N (1..7, lsm303dlhc_mag_range_t); answers `ok`
 *   q       end the run (exit code 0)
 * Prints `ready` at start. */
#include <stdbool.h>
#include <stdint.h>

#include "board.h"
#include "board_text.h"
#include "lsm303dlhc_mag.h"

#define LINE_MAX 16u

static void print(const char *text) {
  size_t length = 0u;
  while (text[length] != '\0') {
    length++;
  }
  board_uart0_write(text, length);
}

static void print_int(int32_t value) {
  char digits[BOARD_TEXT_U32_MAX];
  print(value < 0 ? " -" : " ");
  board_text_u32(value < 0 ? (uint32_t)(-(int64_t)value) : (uint32_t)value, digits);
  print(digits);
}

static void print_float_bits(float value) {
  char bits[9];
  board_text_float_bits(value, bits);
  print(" ");
  print(bits);
}

static void read_once(lsm303dlhc_mag_t *const mag) {
  int16_t counts[3] = {0, 0, 0};
  float field_ut[3] = {0.0f, 0.0f, 0.0f};
  lsm303dlhc_mag_status_t status = lsm303dlhc_mag_read_counts(mag, counts);
  if (status == LSM303DLHC_MAG_OK) {
    for (unsigned axis = 0u; axis < 3u; axis++) {
      field_ut[axis] = (float)counts[axis] * lsm303dlhc_mag_ut_per_count(mag->settings.range, axis);
    }
  }
  print("mag");
  print_int((int32_t)status);
  for (unsigned axis = 0u; axis < 3u; axis++) {
    print_int(counts[axis]);
  }
  for (unsigned axis = 0u; axis < 3u; axis++) {
    print_float_bits(field_ut[axis]);
  }
  print("\n");
}

static uint32_t parse_hex(const char *text) {
  uint32_t value = 0u;
  for (; *text != '\0'; text++) {
    const char c = *text;
    const uint32_t digit = c >= '0' && c <= '9'   ? (uint32_t)(c - '0')
                           : c >= 'a' && c <= 'f' ? (uint32_t)(c - 'a' + 10)
                           : c >= 'A' && c <= 'F' ? (uint32_t)(c - 'A' + 10)
                                                  : 0u;
    value = value * 16u + digit;
  }
  return value;
}

/* Blocks until a whole line arrived on UART0 (without its end). */
static void receive_line(char line[LINE_MAX]) {
  size_t length = 0u;
  for (;;) {
    board_rx_t received;
    if (!board_uart0_receive(&received)) {
      continue;
    }
    if (received.character == '\n' || received.character == '\r') {
      if (length > 0u) {
        line[length] = '\0';
        return;
      }
    } else if (length + 1u < LINE_MAX) {
      line[length++] = received.character;
    }
  }
}

int main(void) {
  board_init();
  bus_t bus;
  board_i2c_init(&bus);
  lsm303dlhc_mag_settings_t settings = lsm303dlhc_mag_settings_default;
  uint8_t address = LSM303DLHC_MAG_ADDRESS;
  lsm303dlhc_mag_t mag;
  lsm303dlhc_mag_init(&mag, &bus, address, &settings);
  print("ready\n");
  for (;;) {
    char line[LINE_MAX];
    receive_line(line);
    if (line[0] == 'q') {
      return 0;
    }
    if (line[0] == 'r') {
      read_once(&mag);
      continue;
    }
    if (line[0] == 'a' && line[1] == ' ') {
      address = (uint8_t)parse_hex(&line[2]);
    } else if (line[0] == 'g' && line[1] == ' ') {
      settings.range = (lsm303dlhc_mag_range_t)parse_hex(&line[2]);
    } else {
      print("refused\n");
      continue;
    }
    lsm303dlhc_mag_init(&mag, &bus, address, &settings);
    print("ok\n");
  }
}
