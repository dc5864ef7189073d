/* I2C controller registers and bits (RM0440 "I2C registers"), for g4_i2c*.c. */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_I2C_REGS_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_I2C_REGS_H

#include "g4_regs.h"

#define I2C_CR1(base) G4_REG((base) + 0x00u)
#define I2C_CR2(base) G4_REG((base) + 0x04u)
#define I2C_TIMINGR(base) G4_REG((base) + 0x10u)
#define I2C_ISR(base) G4_REG((base) + 0x18u)
#define I2C_ICR(base) G4_REG((base) + 0x1Cu)
#define I2C_RXDR(base) G4_REG((base) + 0x24u)
#define I2C_TXDR(base) G4_REG((base) + 0x28u)

#define I2C_CR1_PE (1u << 0)
#define I2C_CR2_RD_WRN (1u << 10)
#define I2C_CR2_START (1u << 13)
#define I2C_CR2_STOP (1u << 14)
#define I2C_CR2_NBYTES_SHIFT 16u
#define I2C_CR2_RELOAD (1u << 24)
#define I2C_CR2_AUTOEND (1u << 25)
#define I2C_NBYTES_MAX 255u

#define I2C_ISR_TXE (1u << 0)
#define I2C_ISR_TXIS (1u << 1)
#define I2C_ISR_RXNE (1u << 2)
#define I2C_ISR_NACKF (1u << 4)
#define I2C_ISR_STOPF (1u << 5)
#define I2C_ISR_TC (1u << 6)
#define I2C_ISR_TCR (1u << 7)
#define I2C_ISR_BERR (1u << 8)
#define I2C_ISR_ARLO (1u << 9)
#define I2C_ISR_OVR (1u << 10)
#define I2C_ISR_BUSY (1u << 15)
#define I2C_ISR_ERRORS (I2C_ISR_BERR | I2C_ISR_ARLO | I2C_ISR_OVR)
/* ICR clear bits sit at the same positions as their ISR flags. */
#define I2C_ICR_ALL (I2C_ISR_NACKF | I2C_ISR_STOPF | I2C_ISR_ERRORS | (1u << 3))

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_I2C_REGS_H */
