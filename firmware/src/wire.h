/*
 * wire.h -- the DAQ frame format (docs/wire-protocol.md), firmware side.
 *
 * The Python side is src/slipreflex/devices/wire.py; tests/test_firmware.py checks that
 * the constants below equal the Python ones, and firmware/test/test_vectors.c checks
 * this encoder against tests/data/wire/vectors.txt.  Portable C: builds for the AVR and
 * for the host.
 */
#ifndef SLIPREFLEX_WIRE_H
#define SLIPREFLEX_WIRE_H

#include <stdint.h>

#define WIRE_SYNC0 0xA5u
#define WIRE_SYNC1 0x5Au
#define WIRE_VERSION 1u
#define WIRE_FRAME_LEN 20u
#define WIRE_BAUD 250000UL
#define WIRE_ADC_MAX 1023u
#define WIRE_FLAG_ACCEL_FRESH 0x01u
#define WIRE_FLAG_IMU_ERROR 0x02u
#define WIRE_FLAG_OVERRUN 0x04u

/* One sample period's values, in the board's raw units. */
struct wire_sample {
    uint16_t seq;
    uint8_t flags;
    uint16_t adc;
    int16_t accel[3];   /* x, y, z; sent as 0 unless flags has WIRE_FLAG_ACCEL_FRESH */
    uint32_t flow;      /* cumulative flow-sensor pulses */
};

/* CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, not reflected, no final xor. */
uint16_t wire_crc16(uint16_t crc, const uint8_t *data, uint8_t len);

/* Write the 20-byte frame of `s` into `out`. */
void wire_encode(uint8_t out[WIRE_FRAME_LEN], const struct wire_sample *s);

#endif
