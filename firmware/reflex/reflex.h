/*
 * reflex.h -- the slip reflex chain (docs/method.md section 1) in integer fixed point.
 *
 * Portable C99: no AVR header, no floating point, no dynamic memory. The caller owns
 * the parameters and the state (as in PyWavelets' C core), so several chains can run
 * side by side and the host tests can run the very code the board runs. The Python
 * twin, slipreflex.methods.board, does the same integer operations; tests/data/board/vectors.txt
 * holds inputs and outputs that both must reproduce bit for bit (docs/firmware.md,
 * "The reflex on the board", states every format, rounding and overflow bound).
 *
 *   ADC counts (10 bit) -> 2nd-order Butterworth low-pass, direct form I,
 *   coefficients Q24, output Q16 counts -> send-on-delta encoder (fixed threshold or
 *   DATH) on Q16 counts -> spike count per window of n samples -> MPI controller
 *   on integers -> finger command (int16, i-Limb units).
 *
 * Numbers: the filter's coefficients are REFLEX_COEF_Q = 24 fractional bits; signals
 * (filtered samples, thresholds, accumulator) are counts with REFLEX_SIG_Q = 16
 * fractional bits. The one rounding of the chain is at the filter output: the Q40
 * accumulator is rounded half up (add 2^23, arithmetic shift right by 24).
 */
#ifndef SLIPREFLEX_REFLEX_H
#define SLIPREFLEX_REFLEX_H

#include <stdint.h>

#define REFLEX_COEF_Q 24
#define REFLEX_SIG_Q 16
#define REFLEX_ADC_MAX 1023u
#define REFLEX_H_MAX 65535u      /* the integral saturates here (output-neutral, see docs) */

/* Everything fixed for a run, in the chain's integer units. */
struct reflex_params {
    int32_t g, a1, a2;        /* low-pass, Q24: b = g (1, 2, 1), a = (1, a1, a2),
                                 4 g = 2^24 + a1 + a2 (DC gain exactly 1) */
    int32_t theta0;           /* base threshold, Q16 counts (0.008 V -> 107374) */
    int32_t dath_floor;       /* DATH floor, Q16 counts */
    int32_t x0;               /* initial reference, Q16 counts, if x0_given */
    int16_t p0, lo, hi;       /* initial position, saturation range (i-Limb units) */
    uint16_t adc_min, adc_max;  /* a reading outside [adc_min, adc_max] is a fault */
    uint16_t stuck_after;     /* > 0: a reading equal to the previous stuck_after
                                 readings is a fault (0: off) */
    uint8_t filter;           /* 0: no low-pass, x = adc << 16 */
    uint8_t dath;             /* 1: Dynamic Adaptive Threshold */
    uint8_t dath_samples;     /* DATH duration D >= 1 */
    uint8_t x0_given;         /* 0: the reference starts at the first filtered sample */
    uint8_t n;                /* samples per window >= 1 */
    uint8_t kp, ki;           /* MPI gains */
    uint8_t reset_after;      /* zero windows before P0 and the integral reset >= 1 */
};

/* Everything that changes, owned by the caller; reflex_init() sets it. */
struct reflex_state {
    int32_t y1, y2;           /* last two filter outputs, Q16 */
    int32_t x;                /* last filtered sample, Q16 (kept over faults) */
    int32_t prev, acc, theta; /* encoder, Q16 */
    int16_t r1, r2;           /* last two filter inputs, counts */
    int16_t P0, m;            /* MPI: base position, last command */
    uint16_t h;               /* MPI integral of spike counts, saturating */
    uint16_t last_adc, same;  /* previous reading and how many times it repeated */
    uint8_t remaining;        /* DATH samples left */
    uint8_t primed;           /* filter and encoder hold a valid state */
    uint8_t started;          /* a valid sample has been seen since reflex_init */
    uint8_t in_window, count; /* samples and spikes in the current window */
    uint8_t zeros;            /* zero windows in a row */
};

/* What one sample produced. */
struct reflex_out {
    int16_t command;          /* the command in force after this sample */
    uint8_t event;            /* spike y_k */
    uint8_t window;           /* 1: this sample completed a window */
    uint8_t v;                /* spikes in that window (valid when window) */
    uint8_t fault;            /* 1: the reading was out of range or stuck, skipped */
};

/* Initial state: P0 = p0, command = clip(p0), nothing seen yet. */
void reflex_init(struct reflex_state *st, const struct reflex_params *p);

/* One ADC reading in. `position` is the hand's measured slip-finger position, used as
 * P0 when the MPI resets, or NULL (then the last command is used). Returns out->window. */
uint8_t reflex_step(struct reflex_state *st, const struct reflex_params *p, uint16_t adc,
                    const int16_t *position, struct reflex_out *out);

#endif
