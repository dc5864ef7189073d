/* The LM3S6965's peripheral registers the board uses (datasheet DS-LM3S6965), by
 * address. QEMU's lm3s6965evb models them (QEMU 7.2: hw/arm/stellaris.c, PL011, PL061). */
#ifndef FIRMWARE_BOARDS_LM3S6965EVB_LM3S6965_H
#define FIRMWARE_BOARDS_LM3S6965EVB_LM3S6965_H

#include <stdint.h>

#define LM3S_REG(address) (*(volatile uint32_t *)(address))

/* System control: clock tree and peripheral clock gates. */
#define SYSCTL_RIS LM3S_REG(0x400FE050u)
#define SYSCTL_RIS_PLLLRIS (1u << 6)
#define SYSCTL_RCC LM3S_REG(0x400FE060u)
#define SYSCTL_RCC_BYPASS (1u << 11)
#define SYSCTL_RCC_PWRDN (1u << 13)
#define SYSCTL_RCC_USESYSDIV (1u << 22)
#define SYSCTL_RCC_XTAL_MASK (0xFu << 6)
#define SYSCTL_RCC_XTAL_8MHZ (0xEu << 6)
#define SYSCTL_RCC_OSCSRC_MASK (0x3u << 4)
#define SYSCTL_RCC_SYSDIV_MASK (0xFu << 23)
#define SYSCTL_RCC_SYSDIV(divisor) ((uint32_t)((divisor) - 1u) << 23)
#define SYSCTL_RCGC1 LM3S_REG(0x400FE104u)
#define SYSCTL_RCGC1_UART0 (1u << 0)
#define SYSCTL_RCGC1_UART1 (1u << 1)
#define SYSCTL_RCGC1_I2C0 (1u << 12)
#define SYSCTL_RCGC2 LM3S_REG(0x400FE108u)
#define SYSCTL_RCGC2_GPIOA (1u << 0)
#define SYSCTL_RCGC2_GPIOB (1u << 1)
#define SYSCTL_RCGC2_GPIOD (1u << 3)

/* GPIO ports (pin functions): alternate function, open drain, digital enable. */
#define GPIO_PORTA 0x40004000u
#define GPIO_PORTB 0x40005000u
#define GPIO_PORTD 0x40007000u
#define GPIO_AFSEL(port) LM3S_REG((port) + 0x420u)
#define GPIO_ODR(port) LM3S_REG((port) + 0x50Cu)
#define GPIO_DEN(port) LM3S_REG((port) + 0x51Cu)

/* UARTs (ARM PL011). */
#define UART0 0x4000C000u
#define UART1 0x4000D000u
#define UART_DR(uart) LM3S_REG((uart) + 0x000u)
#define UART_FR(uart) LM3S_REG((uart) + 0x018u)
#define UART_FR_RXFE (1u << 4)
#define UART_FR_TXFF (1u << 5)
#define UART_IBRD(uart) LM3S_REG((uart) + 0x024u)
#define UART_FBRD(uart) LM3S_REG((uart) + 0x028u)
#define UART_LCRH(uart) LM3S_REG((uart) + 0x02Cu)
#define UART_LCRH_FEN (1u << 4)
#define UART_LCRH_WLEN_8 (3u << 5)
#define UART_CTL(uart) LM3S_REG((uart) + 0x030u)
#define UART_CTL_UARTEN (1u << 0)
#define UART_CTL_TXE (1u << 8)
#define UART_CTL_RXE (1u << 9)
#define UART_IM(uart) LM3S_REG((uart) + 0x038u)
#define UART_ICR(uart) LM3S_REG((uart) + 0x044u)
#define UART_INT_RX (1u << 4)
#define UART_INT_RT (1u << 6)
#define UART0_IRQ 5u
#define UART1_IRQ 6u

/* I2C0 master. */
#define I2C0_MSA LM3S_REG(0x40020000u)
#define I2C0_MCS LM3S_REG(0x40020004u)
#define I2C0_MDR LM3S_REG(0x40020008u)
#define I2C0_MTPR LM3S_REG(0x4002000Cu)
#define I2C0_MCR LM3S_REG(0x40020020u)
#define I2C_MCR_MFE (1u << 4)
/* MCS written: commands. */
#define I2C_MCS_RUN (1u << 0)
#define I2C_MCS_START (1u << 1)
#define I2C_MCS_STOP (1u << 2)
#define I2C_MCS_ACK (1u << 3)
/* MCS read: status. */
#define I2C_MCS_BUSY (1u << 0)
#define I2C_MCS_ERROR (1u << 1)
#define I2C_MCS_ADRACK (1u << 2)
#define I2C_MCS_DATACK (1u << 3)
#define I2C_MCS_ARBLST (1u << 4)

#define LM3S_IRQS 48u

#endif /* FIRMWARE_BOARDS_LM3S6965EVB_LM3S6965_H */
