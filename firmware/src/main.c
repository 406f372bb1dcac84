/*
 * main.c -- slipreflex DAQ firmware for an ATmega328P at 16 MHz (Arduino Uno class).
 *
 * Every 3 ms (Timer1 CTC, 333.33 Hz) the Timer1 interrupt starts an ADC conversion of
 * the slip sensor on ADC0 and one MPU6050 transaction on the TWI bus. The ADC interrupt
 * takes a snapshot (ADC value, latest accelerometer reading, flow-pulse count); the
 * main loop turns it into a 20-byte frame (docs/wire-protocol.md) and appends it to a
 * ring buffer that the UART data-register-empty interrupt drains at 250000 baud.
 * INT0 counts the YF-S201 flow-sensor pulses. No interrupt waits for anything.
 *
 * Pins: A0/PC0 slip sensor (0..5 V), A4/PC4 SDA and A5/PC5 SCL to the MPU6050,
 * D2/PD2 (INT0) YF-S201 signal, D1/PD1 (TXD) to the USB-serial bridge. See
 * docs/firmware.md.
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <avr/wdt.h>
#include <util/atomic.h>

#include "imu.h"
#include "wire.h"

#ifndef F_CPU
#error "F_CPU must be defined (16000000UL)"
#endif

/* Sample period: 3 ms = (OCR1A + 1) x 8 / F_CPU, exact at 16 MHz. */
#define PERIOD_US 3000UL
#define TIMER1_PRESCALE 8UL
#define TIMER1_TOP ((unsigned long)((unsigned long long)F_CPU / TIMER1_PRESCALE * PERIOD_US \
                                    / 1000000ULL) - 1UL)                  /* 5999 */
_Static_assert((unsigned long long)F_CPU / TIMER1_PRESCALE * PERIOD_US % 1000000ULL == 0
               && TIMER1_TOP < 65536UL,
               "the 3 ms period is not a whole number of timer ticks");
#ifdef WRONG_PERIOD
/* Negative-control build for the tests: an off-by-one compare value (3.0005 ms). */
#define OCR1A_VALUE (TIMER1_TOP + 1UL)
#else
#define OCR1A_VALUE TIMER1_TOP
#endif

/* UART divider: exact when F_CPU is a multiple of 16 x baud (U2X0 = 0). */
_Static_assert(F_CPU % (16UL * WIRE_BAUD) == 0, "baud divider is not exact at F_CPU");
#define UBRR_VALUE (F_CPU / (16UL * WIRE_BAUD) - 1UL)                        /* 3 */

/* Transmit ring: 64 bytes = 3 frames. A frame takes 0.8 ms on the wire, a period is
 * 3 ms, so at most one frame is ever queued; a frame is only queued when it fits
 * whole, so the buffer cannot overflow even if the host stops reading (frames are then
 * dropped, flagged OVERRUN, and the seq gap shows). */
#define TX_SIZE 64u
#define TX_MASK (TX_SIZE - 1u)
_Static_assert((TX_SIZE & TX_MASK) == 0 && TX_SIZE >= 2u * WIRE_FRAME_LEN, "TX ring size");
static uint8_t tx_buf[TX_SIZE];
static volatile uint8_t tx_head;     /* written by the main loop */
static volatile uint8_t tx_tail;     /* written by the UDRE interrupt */

/* The snapshot handed from the ADC interrupt to the main loop. */
static struct wire_sample snap;
static volatile uint8_t snap_ready;
static uint16_t next_seq;
static volatile uint32_t flow_count;
static volatile uint8_t overrun;     /* WIRE_FLAG_OVERRUN for the next frame */

#define ADCSRA_ON (_BV(ADEN) | _BV(ADIE) | _BV(ADPS2) | _BV(ADPS1) | _BV(ADPS0)) /* 125 kHz */

ISR(TIMER1_COMPA_vect)
{
    if (ADCSRA & _BV(ADSC))
        overrun = WIRE_FLAG_OVERRUN;     /* previous conversion still running */
    else
        ADCSRA = ADCSRA_ON | _BV(ADSC);  /* sample-and-hold 1.5 ADC clocks from now */
    imu_tick();
}

ISR(ADC_vect)
{
    if (snap_ready)                      /* main loop did not frame the last one */
        overrun = WIRE_FLAG_OVERRUN;
    snap.seq = next_seq++;
    snap.adc = ADC;
    snap.flow = flow_count;
    snap.flags = imu_take(snap.accel) | overrun;
    overrun = 0;
    snap_ready = 1;
}

ISR(INT0_vect)
{
    flow_count++;
}

ISR(USART_UDRE_vect)
{
    uint8_t t = tx_tail;
    UDR0 = tx_buf[t];
    t = (t + 1u) & TX_MASK;
    tx_tail = t;
    if (t == tx_head)
        UCSR0B &= (uint8_t)~_BV(UDRIE0);
}

static void tx_frame(const uint8_t *frame)
{
    uint8_t h = tx_head;
    uint8_t used = (uint8_t)(h - tx_tail) & TX_MASK;
    if (TX_SIZE - 1u - used < WIRE_FRAME_LEN) {
        overrun = WIRE_FLAG_OVERRUN;     /* host not draining: drop, never overflow */
        return;
    }
    for (uint8_t i = 0; i < WIRE_FRAME_LEN; i++) {
        tx_buf[h] = frame[i];
        h = (h + 1u) & TX_MASK;
    }
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
        tx_head = h;
        UCSR0B |= _BV(UDRIE0);
    }
}

static void setup(void)
{
    /* UART: 250000 8N1, transmit only. */
    UBRR0H = (uint8_t)(UBRR_VALUE >> 8);
    UBRR0L = (uint8_t)UBRR_VALUE;
    UCSR0A = 0;
    UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
    UCSR0B = _BV(TXEN0);

    /* ADC: AVcc reference, channel 0, digital input buffer of ADC0 off. */
    ADMUX = _BV(REFS0);
    DIDR0 = _BV(ADC0D);
    ADCSRA = ADCSRA_ON;

    /* Flow sensor on INT0 (PD2), falling edge, pull-up on (open-collector output). */
    DDRD &= (uint8_t)~_BV(PD2);
    PORTD |= _BV(PD2);
    EICRA = _BV(ISC01);
    EIFR = _BV(INTF0);
    EIMSK = _BV(INT0);

    imu_init();

    /* Timer1: CTC on OCR1A, clock / 8 -> 2 MHz, compare every 6000 ticks. */
    TCCR1A = 0;
    TCNT1 = 0;
    OCR1A = (uint16_t)OCR1A_VALUE;
    TIMSK1 = _BV(OCIE1A);
    TCCR1B = _BV(WGM12) | _BV(CS11);
}

int main(void)
{
    MCUSR = 0;                           /* clear WDRF so the watchdog can be re-set */
    wdt_enable(WDTO_60MS);
    setup();
    set_sleep_mode(SLEEP_MODE_IDLE);     /* timers, ADC, TWI and UART keep running */
    sei();
    for (;;) {
        struct wire_sample s;
        wdt_reset();
        cli();
        if (!snap_ready) {
            sleep_enable();
            sei();                       /* the instruction after SEI always runs: */
            sleep_cpu();                 /* no wake-up can be lost in between */
            sleep_disable();
            continue;
        }
        s = snap;
        snap_ready = 0;
        sei();
        uint8_t frame[WIRE_FRAME_LEN];
        wire_encode(frame, &s);
        tx_frame(frame);
    }
}
