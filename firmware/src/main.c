/*
 * main.c -- slipreflex DAQ firmware for an ATmega328P at 16 MHz (Arduino Uno class).
 *
 * Every 3 ms (Timer1 CTC, 333.33 Hz) the Timer1 interrupt starts an ADC conversion of
 * the slip sensor on ADC0 and one MPU6050 transaction on the TWI bus. The ADC interrupt
 * does the rest of the sample at once: it takes the ADC value, the latest accelerometer
 * reading and the flow-pulse count, runs the reflex chain (reflex builds), encodes the
 * 20-byte frame (28 with the reflex; docs/wire-protocol.md) and starts sending it; the
 * UART data-register-empty interrupt sends the rest at 250000 baud. INT0 counts the
 * YF-S201 flow-sensor pulses. The main loop only sleeps; nothing waits for anything.
 *
 * Pins: A0/PC0 slip sensor (0..5 V), A4/PC4 SDA and A5/PC5 SCL to the MPU6050,
 * D2/PD2 (INT0) YF-S201 signal, D1/PD1 (TXD) to the USB-serial bridge. See
 * docs/firmware.md.
 *
 * Build options (firmware/Makefile):
 *   REFLEX_ON_BOARD  the main loop also runs the reflex chain (firmware/reflex/) on every
 *                    ADC reading and sends version-2 frames carrying its spike, window
 *                    count, command and filtered sample. REFLEX_DATH (0/1) and REFLEX_P0
 *                    choose the encoder and the initial position.
 *   HAND_UART1       (ATmega2560, with REFLEX_ON_BOARD) the standalone reflex: each rise
 *                    of the command becomes closing time for the tripod, i-Limb CLOSE
 *                    (full PWM) then STOP packets on UART1 at 115200 baud; a fault and
 *                    every start send STOP; never OPEN or POSITION. On the ATmega2560 (Arduino Mega) the pins are
 *                    A0/PF0 slip sensor, D20/PD1 SDA, D21/PD0 SCL, D2/PE4 (INT4) flow
 *                    sensor, D1/PE1 TXD0 to the PC, D18/PD3 TXD1 to the hand.
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <avr/wdt.h>
#include <stddef.h>

#include "imu.h"
#include "wire.h"
#ifdef REFLEX_ON_BOARD
#include "reflex.h"
#include "reflex_config.h"
#endif
#if defined(HAND_UART1) && !(defined(REFLEX_ON_BOARD) && defined(UDR1))
#error "HAND_UART1 needs REFLEX_ON_BOARD and a second UART (ATmega2560)"
#endif

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

#ifdef REFLEX_ON_BOARD
#define FRAME_LEN WIRE_FRAME_LEN_REFLEX
#else
#define FRAME_LEN WIRE_FRAME_LEN
#endif

/* Transmit: one frame buffer. A frame takes 0.8 ms on the wire (1.12 ms for version 2)
 * and one is made every 3 ms, so the previous frame is always gone when the next one
 * is ready; should it not be, the new frame is dropped, the next one carries OVERRUN
 * and the seq gap shows: the buffer can never overflow. The UDRE interrupt is enabled
 * exactly while a frame is going out; its read pointer lives in GPIOR1:GPIOR2, I/O
 * registers it reads and writes in one cycle each. */
static uint8_t tx_buf[FRAME_LEN];
#define TX_BUSY() (UCSR0B & _BV(UDRIE0))

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

#if defined(__AVR_ATmega2560__)
#define FLOW_VECT INT4_vect          /* Mega pin D2 = PE4; INT0/INT1 are the TWI pins there */
#else
#define FLOW_VECT INT0_vect          /* Uno pin D2 = PD2 */
#endif
ISR(FLOW_VECT)
{
    flow_count++;
}

#ifndef USART_UDRE_vect
#define USART_UDRE_vect USART0_UDRE_vect   /* the ATmega2560 numbers its UARTs */
#endif
/* One byte out per interrupt, 19 (27) times per frame: hand-written because the
 * compiler's version (49 cycles) was a third of the DAQ's CPU time; this is 33. */
ISR(USART_UDRE_vect, ISR_NAKED)
{
    __asm__ __volatile__(
        "push r24\n\t"
        "in r24, __SREG__\n\t"
        "push r24\n\t"
        "push r30\n\t"
        "push r31\n\t"
        "in r30, %[ptr_lo]\n\t"
        "in r31, %[ptr_hi]\n\t"
        "ld r24, Z+\n\t"
        "sts %[udr], r24\n\t"
        "out %[ptr_lo], r30\n\t"
        "out %[ptr_hi], r31\n\t"
        "cpi r30, lo8(%[end])\n\t"       /* the buffer spans < 256 bytes: low byte suffices */
        "brne 1f\n\t"
        "lds r24, %[ucsrb]\n\t"          /* frame done: no more UDRE interrupts */
        "andi r24, %[no_udrie]\n\t"
        "sts %[ucsrb], r24\n"
        "1:\n\t"
        "pop r31\n\t"
        "pop r30\n\t"
        "pop r24\n\t"
        "out __SREG__, r24\n\t"
        "pop r24\n\t"
        "reti\n\t"
        :: [ptr_lo] "I" (_SFR_IO_ADDR(GPIOR1)), [ptr_hi] "I" (_SFR_IO_ADDR(GPIOR2)),
           [udr] "n" (_SFR_MEM_ADDR(UDR0)), [ucsrb] "n" (_SFR_MEM_ADDR(UCSR0B)),
           [end] "i" (tx_buf + FRAME_LEN), [no_udrie] "n" (0xFF & ~_BV(UDRIE0)));
}

/* Start sending tx_buf: the first byte goes straight into the empty data register
 * (the line is idle), the UDRE interrupt sends the rest. Interrupt context. */
static inline void tx_start(void)
{
    const uint8_t *next = tx_buf + 1;
    UDR0 = tx_buf[0];
    GPIOR1 = (uint8_t)(uintptr_t)next;
    GPIOR2 = (uint8_t)((uintptr_t)next >> 8);
    UCSR0B |= _BV(UDRIE0);
}

#ifdef REFLEX_ON_BOARD
#ifndef REFLEX_DATH
#define REFLEX_DATH 1
#endif
#ifndef REFLEX_P0
#define REFLEX_P0 0
#endif
/* Fault rules (reflex_config.h, from slipreflex.methods.board.FIRMWARE_*): readings near the
 * rails mean a disconnected or shorted sensor, a long run of identical readings a stuck
 * converter or a dead sensor; the chain skips them and the hand holds. */
static const struct reflex_params chain_params = {
    .g = REFLEX_CFG_G, .a1 = REFLEX_CFG_A1, .a2 = REFLEX_CFG_A2,
    .theta0 = REFLEX_CFG_THETA0, .dath_floor = 0, .x0 = 0,
    .p0 = REFLEX_P0, .lo = REFLEX_CFG_LO, .hi = REFLEX_CFG_HI,
    .adc_min = REFLEX_CFG_ADC_MIN, .adc_max = REFLEX_CFG_ADC_MAX,
    .stuck_after = REFLEX_CFG_STUCK_AFTER,
    .filter = 1, .dath = REFLEX_DATH, .dath_samples = REFLEX_CFG_DATH_SAMPLES, .x0_given = 0,
    .n = REFLEX_CFG_N, .kp = REFLEX_CFG_KP, .ki = REFLEX_CFG_KI,
    .reset_after = REFLEX_CFG_RESET_AFTER,
};
static struct reflex_state chain;
#endif

#ifdef HAND_UART1
/* i-Limb control unit on UART1, 8N1 at 115200 baud: with U2X1 the nearest divider at
 * 16 MHz is UBRR1 = 16, i.e. 117647 baud, +2.12 % (docs/firmware.md).
 *
 * Grip only ever added (docs/firmware.md, "The hand: grip only added"): the command is
 * never sent as a position. A window whose command rises g units above grip_level owes
 * g units of closing at full PWM, g / 625 s = 8 g / 15 samples; grip_left counts the
 * closing still owed in fifteenths of a sample. CLOSE goes out when the fingers are to
 * close, STOP when their time is up or a fault starts; never OPEN, never POSITION. The
 * Python twin is slipreflex.methods.board.BoardHand. */
#define HAND_BAUD 115200UL
#define HAND_UBRR ((F_CPU + 4UL * HAND_BAUD) / (8UL * HAND_BAUD) - 1UL)           /* 16 */
#define HAND_START 0x24u
#define HAND_END 0x21u
#define HAND_STOP 0u
#define HAND_CLOSE 1u
#define HAND_FINGERS 3u                   /* tripod: thumb 0, index 1, middle 2 */
#define HAND_PACKET_LEN (3u + 4u * HAND_FINGERS)
static uint8_t hand_buf[HAND_PACKET_LEN];
static volatile uint8_t hand_idx = HAND_PACKET_LEN;   /* == LEN: nothing in flight */
/* The command already turned into grip survives a watchdog reset (.noinit, with its
 * complement as a check): a reset board's MPI resumes from it (bookkeeping only). */
static int16_t grip_level __attribute__((section(".noinit")));
static uint16_t grip_level_check __attribute__((section(".noinit")));
static int32_t grip_left;                 /* closing owed, 1/15 sample; <= 0 when stopped */
static uint8_t hand_closing;              /* the last packet sent was CLOSE */
static uint8_t hand_fault;                /* the last reading was faulty */

ISR(USART1_UDRE_vect)
{
    uint8_t i = hand_idx;
    UDR1 = hand_buf[i++];
    hand_idx = i;
    if (i == HAND_PACKET_LEN)
        UCSR1B &= (uint8_t)~_BV(UDRIE1);
}

static void hand_setup(void)
{
    UBRR1H = (uint8_t)(HAND_UBRR >> 8);
    UBRR1L = (uint8_t)HAND_UBRR;
    UCSR1A = _BV(U2X1);
    UCSR1C = _BV(UCSZ11) | _BV(UCSZ10);
    UCSR1B = _BV(TXEN1);
}

/* Queue CLOSE (full PWM) or STOP for the tripod. A packet takes 1.28 ms on the wire and
 * at most one is queued per 3 ms sample, so the previous one is always gone; should it
 * not be, nothing is queued and the caller tries again at the next sample. Returns 1 if
 * queued. */
static uint8_t hand_send(uint8_t command)
{
    if (hand_idx != HAND_PACKET_LEN)
        return 0;
    uint16_t value = command == HAND_CLOSE ? REFLEX_CFG_HAND_PWM : 0u;
    uint8_t *p = hand_buf;
    *p++ = HAND_START;
    *p++ = 4u * HAND_FINGERS;
    for (uint8_t f = 0; f < HAND_FINGERS; f++) {
        *p++ = f;
        *p++ = command;
        *p++ = (uint8_t)(value >> 8);
        *p++ = (uint8_t)value;
    }
    *p = HAND_END;
    hand_idx = 0;
    UCSR1B |= _BV(UDRIE1);
    return 1;
}

/* After each sample: the grip-only rule (slipreflex.methods.board.BoardHand, step by step).
 * Returns 1 if a packet was queued. */
static uint8_t hand_step(const struct reflex_out *out)
{
    if (hand_closing)
        grip_left -= REFLEX_CFG_GRIP_PER_SAMPLE;          /* one sample of closing done */
    if (out->window && out->command > grip_level) {
        grip_left += (int32_t)REFLEX_CFG_GRIP_PER_UNIT * ((int32_t)out->command - grip_level);
        grip_level = out->command;
        grip_level_check = (uint16_t)~(uint16_t)grip_level;
    }
#ifdef HAND_WRONG_ROUNDING
    /* Negative control for the tests: closing time rounded down (floor), not up. */
    uint8_t want = grip_left >= REFLEX_CFG_GRIP_PER_SAMPLE && !out->fault;
#else
    uint8_t want = grip_left > 0 && !out->fault;
#endif
    uint8_t onset = out->fault && !hand_fault;
    uint8_t sent = 0;
    if (want && !hand_closing)
        sent = hand_send(HAND_CLOSE);
    else if ((hand_closing && !want) || onset)
        sent = hand_send(HAND_STOP);
    else
        want = hand_closing;             /* nothing to send: nothing changes */
    if (want != hand_closing || onset) {
        if (!sent)
            return 0;                    /* UART1 busy (cannot happen): again next sample */
        hand_closing = want;
    }
    hand_fault = out->fault;
    if (!hand_closing && grip_left < 0)
        grip_left = 0;
    return sent;
}
#endif

/* The end of a conversion: everything about the sample happens here, at once, so the
 * main loop only sleeps (every other interrupt then costs no main-loop pass). With the
 * reflex on board the chain runs here too (about 2,300 cycles, 0.15 ms); other
 * interrupts wait meanwhile, which only stretches the I2C clock and delays the flow
 * counter's increment (its edge stays latched). */
ISR(ADC_vect)
{
    struct wire_sample s = {0};          /* accel stays 0 unless imu_take() fills it */
    wdt_reset();                         /* fed once per sample: a stuck chain resets */
    s.seq = next_seq++;
    s.adc = ADC;
    s.flow = flow_count;
    s.flags = imu_take(s.accel) | overrun;
    overrun = 0;
#ifdef REFLEX_ON_BOARD
    struct reflex_out out;
    struct wire_reflex r;
    reflex_step(&chain, &chain_params, s.adc, NULL, &out);
    r.bits = (uint8_t)((out.event ? WIRE_REFLEX_SPIKE : 0u) |
                       (out.window ? WIRE_REFLEX_WINDOW : 0u) |
                       (out.fault ? WIRE_REFLEX_FAULT : 0u));
#ifdef HAND_UART1
    /* Rises become closing time (CLOSE, then STOP); a faulty reading holds (STOP). */
    if (hand_step(&out))
        r.bits |= WIRE_REFLEX_HAND;
#endif
    r.v = out.v;
    r.command = out.command;
    r.x = chain.x;
#endif
    if (TX_BUSY()) {                     /* the last frame is still going out: drop */
        overrun = WIRE_FLAG_OVERRUN;
        return;
    }
#ifdef REFLEX_ON_BOARD
    wire_encode_reflex(tx_buf, &s, &r);
#else
    wire_encode(tx_buf, &s);
#endif
    tx_start();
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

    /* Flow sensor on INT0 (PD2; INT4/PE4 on the Mega), falling edge, pull-up on
     * (open-collector output). */
#if defined(__AVR_ATmega2560__)
    DDRE &= (uint8_t)~_BV(PE4);
    PORTE |= _BV(PE4);
    EICRB = _BV(ISC41);
    EIFR = _BV(INTF4);
    EIMSK = _BV(INT4);
#else
    DDRD &= (uint8_t)~_BV(PD2);
    PORTD |= _BV(PD2);
    EICRA = _BV(ISC01);
    EIFR = _BV(INTF0);
    EIMSK = _BV(INT0);
#endif
#ifdef HAND_UART1
    hand_setup();
#endif

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
#ifdef HAND_UART1
    uint8_t watchdog_reset = MCUSR & _BV(WDRF);
#endif
    MCUSR = 0;                           /* clear WDRF so the watchdog can be re-set */
    wdt_enable(WDTO_60MS);
#ifdef REFLEX_ON_BOARD
    reflex_init(&chain, &chain_params);
#endif
#ifdef HAND_UART1
    if (!watchdog_reset || (uint16_t)~grip_level_check != (uint16_t)grip_level
        || grip_level > REFLEX_CFG_HI || grip_level < REFLEX_CFG_LO)
        grip_level = chain.m;            /* power-on: no grip added yet, start at clip(p0) */
    else if (grip_level > chain.m)
        chain.m = chain.P0 = grip_level; /* the MPI resumes from the grip already added */
    grip_level_check = (uint16_t)~(uint16_t)grip_level;
#endif
    setup();
#ifdef HAND_UART1
    hand_send(HAND_STOP);                /* every start holds: a reset may cut a closing */
#endif
    set_sleep_mode(SLEEP_MODE_IDLE);     /* timers, ADC, TWI and UART keep running */
    sleep_enable();
    sei();
    for (;;)
        sleep_cpu();                     /* all work happens in interrupts */
}
