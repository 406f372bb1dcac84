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

/* Version byte .. flow (offsets 2..17), shared by both versions; returns the end. */
static uint8_t *put_body(uint8_t *out, uint8_t version, const struct wire_sample *s)
{
    uint8_t fresh = s->flags & WIRE_FLAG_ACCEL_FRESH;
    uint8_t *p = out;
    *p++ = WIRE_SYNC0;
    *p++ = WIRE_SYNC1;
    *p++ = version;
    p = put16(p, s->seq);
    *p++ = s->flags;
    p = put16(p, s->adc);
    for (uint8_t i = 0; i < 3; i++)
        p = put16(p, fresh ? (uint16_t)s->accel[i] : 0u);
    p = put16(p, (uint16_t)s->flow);
    return put16(p, (uint16_t)(s->flow >> 16));
}

/* CRC over bytes 2 .. len-3, appended big-endian: the CRC over bytes 2..len-1 is then 0. */
static void put_crc(uint8_t *out, uint8_t len)
{
    uint16_t crc = wire_crc16(0xFFFFu, out + 2, (uint8_t)(len - 4u));
    out[len - 2u] = (uint8_t)(crc >> 8);
    out[len - 1u] = (uint8_t)crc;
}

void wire_encode(uint8_t out[WIRE_FRAME_LEN], const struct wire_sample *s)
{
    put_body(out, WIRE_VERSION, s);
    put_crc(out, WIRE_FRAME_LEN);
}

void wire_encode_reflex(uint8_t out[WIRE_FRAME_LEN_REFLEX], const struct wire_sample *s,
                        const struct wire_reflex *r)
{
    uint8_t *p = put_body(out, WIRE_VERSION_REFLEX, s);
    *p++ = r->bits;
    *p++ = r->v;
    p = put16(p, (uint16_t)r->command);
    p = put16(p, (uint16_t)(uint32_t)r->x);
    put16(p, (uint16_t)((uint32_t)r->x >> 16));
    put_crc(out, WIRE_FRAME_LEN_REFLEX);
}
