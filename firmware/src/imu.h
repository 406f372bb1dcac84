/*
 * imu.h -- interrupt-driven MPU6050 reader over the TWI (I2C) bus.
 *
 * imu_tick() is called from the Timer1 interrupt once per sample period; it never
 * waits. It starts one bus transaction per call: first the three configuration
 * writes, then one 6-byte accelerometer burst read per period. The TWI interrupt
 * drives the transaction; when a read completes, the reading is left for
 * imu_take() (called from the ADC interrupt when a sample is framed).
 */
#ifndef SLIPREFLEX_IMU_H
#define SLIPREFLEX_IMU_H

#include <stdint.h>

#define IMU_ADDR 0x68u            /* MPU6050 with AD0 low */
#define IMU_TWI_HZ 400000UL       /* fast-mode I2C */
#define IMU_REG_CONFIG 0x1Au      /* DLPF_CFG */
#define IMU_REG_ACCEL_CONFIG 0x1Cu
#define IMU_REG_ACCEL_XOUT_H 0x3Bu
#define IMU_REG_PWR_MGMT_1 0x6Bu
#define IMU_DLPF_CFG 2u           /* accel bandwidth 94 Hz, below the 166 Hz Nyquist */
#define IMU_CLKSEL_PLL_X 1u       /* wake up, clock from the X gyro PLL */
#define IMU_AFS_2G 0u             /* +-2 g, 16384 counts per g */

void imu_init(void);
/* Start this period's transaction (or abort a stuck one). Interrupt context. */
void imu_tick(void);
/* If a reading completed since the last call, copy it to accel and return
 * WIRE_FLAG_ACCEL_FRESH; return WIRE_FLAG_IMU_ERROR if the last transaction
 * failed; 0 otherwise. Interrupt context (or interrupts disabled). */
uint8_t imu_take(int16_t accel[3]);

#endif
