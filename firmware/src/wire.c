/* wire.c -- frame encoder and CRC (see wire.h). */
#include "wire.h"

#ifdef __AVR__
#include <util/crc16.h>
#endif

uint16_t wire_crc16(uint16_t crc, const uint8_t *data, uint8_t len)
{
    while (len--) {
#ifdef __AVR__
        /* avr-libc's XMODEM update is the non-reflected 0x1021 step; started from
         * 0xFFFF it gives CRC-16/CCITT-FALSE (NOT _crc_ccitt_update: reflected). */
        crc = _crc_xmodem_update(crc, *data++);
#else
        crc ^= (uint16_t)((uint16_t)*data++ << 8);
        for (uint8_t bit = 0; bit < 8; bit++)
            crc = (crc & 0x8000u) ? (uint16_t)((crc << 1) ^ 0x1021u) : (uint16_t)(crc << 1);
#endif
    }
    return crc;
}

static uint8_t *put16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    return p + 2;
}

void wire_encode(uint8_t out[WIRE_FRAME_LEN], const struct wire_sample *s)
{
    uint8_t fresh = s->flags & WIRE_FLAG_ACCEL_FRESH;
    uint8_t *p = out;
    *p++ = WIRE_SYNC0;
    *p++ = WIRE_SYNC1;
    *p++ = WIRE_VERSION;
    p = put16(p, s->seq);
    *p++ = s->flags;
    p = put16(p, s->adc);
    for (uint8_t i = 0; i < 3; i++)
        p = put16(p, fresh ? (uint16_t)s->accel[i] : 0u);
    p = put16(p, (uint16_t)s->flow);
    p = put16(p, (uint16_t)(s->flow >> 16));
    uint16_t crc = wire_crc16(0xFFFFu, out + 2, WIRE_FRAME_LEN - 4);
    *p++ = (uint8_t)(crc >> 8);   /* CRC big-endian: CRC over bytes 2..19 is then 0 */
    *p = (uint8_t)crc;
}
