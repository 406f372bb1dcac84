/* imu.c -- see imu.h. All state changes happen in interrupt context. */
#include <avr/io.h>
#include <avr/interrupt.h>

#include "imu.h"
#include "wire.h"

#define TWBR_VALUE ((F_CPU / IMU_TWI_HZ - 16UL) / 2UL)   /* prescaler 1: 12 at 16 MHz */
_Static_assert(TWBR_VALUE > 0 && TWBR_VALUE < 256, "TWI bit rate out of range");

#define TW_START 0x08u
#define TW_REP_START 0x10u
#define TW_MT_SLA_ACK 0x18u
#define TW_MT_DATA_ACK 0x28u
#define TW_MR_SLA_ACK 0x40u
#define TW_MR_DATA_ACK 0x50u
#define TW_MR_DATA_NACK 0x58u

#define TWCR_GO (_BV(TWINT) | _BV(TWEN) | _BV(TWIE))
#define TWCR_STOP (_BV(TWINT) | _BV(TWEN) | _BV(TWSTO))

/* Configuration writes, in order, before the first read; redone after any error. */
static const uint8_t init_seq[][2] = {
    {IMU_REG_PWR_MGMT_1, IMU_CLKSEL_PLL_X},
    {IMU_REG_ACCEL_CONFIG, IMU_AFS_2G << 3},
    {IMU_REG_CONFIG, IMU_DLPF_CFG},
};
#define INIT_STEPS (sizeof init_seq / sizeof init_seq[0])

static volatile uint8_t busy;        /* a transaction is on the bus */
static uint8_t init_step;            /* next configuration write; INIT_STEPS = configured */
static uint8_t wbuf[2], wlen, widx;  /* bytes to write after SLA+W */
static uint8_t reading;              /* this transaction reads the accelerometer */
static uint8_t rbuf[6], ridx;
static uint8_t rx_phase;             /* 1 after the repeated START: send SLA+R */
static int16_t latest[3];
static uint8_t fresh, error;

void imu_init(void)
{
#if defined(__AVR_ATmega2560__)
    PORTD |= _BV(PD0) | _BV(PD1);    /* weak pull-ups on SCL/SDA (boards add 4.7k) */
#else
    PORTC |= _BV(PC4) | _BV(PC5);    /* weak pull-ups on SDA/SCL (boards add 4.7k) */
#endif
    TWSR = 0;                        /* prescaler 1 */
    TWBR = (uint8_t)TWBR_VALUE;
    TWCR = _BV(TWEN);
}

/* Inlined into the TWI interrupt: a call there would make it save 7 more registers on
 * each of the ~11 bus events per period. */
static inline __attribute__((always_inline)) void finish(uint8_t ok)
{
    TWCR = TWCR_STOP;                /* no TWIE: the STOP needs no interrupt */
    busy = 0;
    if (!ok) {
        error = 1;
        init_step = 0;               /* the IMU may have been reset or replugged */
        return;
    }
    error = 0;
    if (reading) {
        for (uint8_t i = 0; i < 3; i++)   /* registers are big-endian */
            latest[i] = (int16_t)(((uint16_t)rbuf[2 * i] << 8) | rbuf[2 * i + 1]);
        fresh = 1;
    } else if (init_step < INIT_STEPS) {
        init_step++;
    }
}

void imu_tick(void)
{
    if (busy) {                      /* a whole period on one transaction: bus stuck */
        TWCR = 0;                    /* reset the TWI unit, release the bus */
        TWCR = _BV(TWEN);
        busy = 0;
        error = 1;
        init_step = 0;
        return;                      /* retry next period */
    }
    if (init_step < INIT_STEPS) {
        wbuf[0] = init_seq[init_step][0];
        wbuf[1] = init_seq[init_step][1];
        wlen = 2;
        reading = 0;
    } else {
        wbuf[0] = IMU_REG_ACCEL_XOUT_H;
        wlen = 1;
        reading = 1;
    }
    widx = ridx = rx_phase = 0;
    busy = 1;
    TWCR = TWCR_GO | _BV(TWSTA);
}

uint8_t imu_take(int16_t accel[3])
{
    if (fresh) {
        accel[0] = latest[0];
        accel[1] = latest[1];
        accel[2] = latest[2];
        fresh = 0;
        return WIRE_FLAG_ACCEL_FRESH;
    }
    return error ? WIRE_FLAG_IMU_ERROR : 0;
}

ISR(TWI_vect)
{
    switch (TWSR & 0xF8u) {
    case TW_START:
    case TW_REP_START:
        TWDR = (uint8_t)((IMU_ADDR << 1) | rx_phase);
        TWCR = TWCR_GO;
        break;
    case TW_MT_SLA_ACK:
    case TW_MT_DATA_ACK:
        if (widx < wlen) {
            TWDR = wbuf[widx++];
            TWCR = TWCR_GO;
        } else if (reading) {
            rx_phase = 1;
            TWCR = TWCR_GO | _BV(TWSTA);          /* repeated START, then SLA+R */
        } else {
            finish(1);
        }
        break;
    case TW_MR_SLA_ACK:
        TWCR = TWCR_GO | _BV(TWEA);               /* ACK all but the last byte */
        break;
    case TW_MR_DATA_ACK:
        if (ridx >= sizeof rbuf - 1u) {           /* cannot happen on a sane bus */
            finish(0);
            break;
        }
        rbuf[ridx++] = TWDR;
        TWCR = (ridx + 1u < sizeof rbuf) ? (TWCR_GO | _BV(TWEA)) : TWCR_GO;
        break;
    case TW_MR_DATA_NACK:
        if (ridx < sizeof rbuf)
            rbuf[ridx++] = TWDR;
        finish(ridx == sizeof rbuf);
        break;
    default:                                      /* NACK, arbitration lost, bus error */
        finish(0);
        break;
    }
}
