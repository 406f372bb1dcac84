/*
 * wire.h -- the DAQ frame format (docs/wire-protocol.md), firmware side.
 *
 * The Python side is src/slipreflex/rig/devices/wire.py; tests/test_firmware.py checks that
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

/* Version 2 (firmware built with the reflex on board): the version-1 fields, then the
 * chain's output for this sample, then the CRC. */
#define WIRE_VERSION_REFLEX 2u
#define WIRE_FRAME_LEN_REFLEX 28u
#define WIRE_REFLEX_SPIKE 0x01u     /* the encoder fired on this sample */
#define WIRE_REFLEX_WINDOW 0x02u    /* this sample completed a window: v is its count */
#define WIRE_REFLEX_FAULT 0x04u     /* reading out of range or stuck: sample skipped */
#define WIRE_REFLEX_HAND 0x08u      /* a hand packet (CLOSE or STOP) was queued */

/* One sample period's values, in the board's raw units. */
struct wire_sample {
    uint16_t seq;
    uint8_t flags;
    uint16_t adc;
    int16_t accel[3];   /* x, y, z; sent as 0 unless flags has WIRE_FLAG_ACCEL_FRESH */
    uint32_t flow;      /* cumulative flow-sensor pulses */
};

/* The chain's output for one sample (version 2 frames). */
struct wire_reflex {
    uint8_t bits;       /* WIRE_REFLEX_* */
    uint8_t v;          /* spikes in the window this sample completed, else 0 */
    int16_t command;    /* finger command in force after this sample */
    int32_t x;          /* filtered sample, Q16 ADC counts */
};

/* CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, not reflected, no final xor.
 * (avr-libc's _crc_xmodem_update started from 0xFFFF computes the same; its
 * _crc_ccitt_update is the reflected variant. wire.c uses a 256-entry table.) */
extern const uint16_t wire_crc_table[256];
uint16_t wire_crc16(uint16_t crc, const uint8_t *data, uint8_t len);

/* Write the 20-byte frame of `s` into `out`. */
void wire_encode(uint8_t out[WIRE_FRAME_LEN], const struct wire_sample *s);

/* Write the 28-byte version-2 frame of `s` and the chain's output `r` into `out`. */
void wire_encode_reflex(uint8_t out[WIRE_FRAME_LEN_REFLEX], const struct wire_sample *s,
                        const struct wire_reflex *r);

#endif
