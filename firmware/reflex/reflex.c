/* reflex.c -- the fixed-point slip reflex chain (see reflex.h and docs/firmware.md). */
#include "reflex.h"

#include <stddef.h>

/* The filter output rounds with an arithmetic right shift of a possibly negative
 * int64 (floor division by 2^24). C99 leaves that implementation-defined; gcc, clang
 * and avr-gcc shift arithmetically; the typedef below (a C99 static assertion) refuses
 * to build where it is not so. */
typedef char reflex_signed_shift_is_arithmetic[(-3 >> 1) == -2 ? 1 : -1];

#ifdef REFLEX_WRONG_ROUNDING
/* Negative control for the tests: truncate (floor) instead of rounding half up. */
#define ROUND_HALF 0
#else
#define ROUND_HALF ((int64_t)1 << (REFLEX_COEF_Q - 1))
#endif

void reflex_init(struct reflex_state *st, const struct reflex_params *p)
{
    int16_t m = p->p0 < p->lo ? p->lo : p->p0 > p->hi ? p->hi : p->p0;
    st->y1 = st->y2 = st->x = 0;
    st->prev = st->acc = 0;
    st->theta = p->theta0;
    st->r1 = st->r2 = 0;
    st->P0 = p->p0;
    st->m = m;
    st->h = 0;
    st->last_adc = 0xFFFFu;   /* no reading equals it: the first one never repeats */
    st->same = 0;
    st->remaining = 0;
    st->primed = st->started = 0;
    st->in_window = st->count = st->zeros = 0;
}

/* Steady state of the first reading after reset or after a fault: a constant input
 * then gives the same constant output from this sample on. */
static void prime(struct reflex_state *st, const struct reflex_params *p, int16_t r)
{
    int32_t xq = (int32_t)r << REFLEX_SIG_Q;
    st->r1 = st->r2 = r;
    st->y1 = st->y2 = xq;
    st->prev = (!st->started && p->x0_given) ? p->x0 : xq;
    st->acc = 0;
    st->theta = p->theta0;
    st->remaining = 0;
    st->primed = st->started = 1;
}

/* Direct form I: y = (g (r + 2 r1 + r2) 2^16 - a1 y1 - a2 y2 + 2^23) >> 24, in Q16. */
static int32_t lowpass(struct reflex_state *st, const struct reflex_params *p, int16_t r)
{
    int32_t s = (int32_t)r + 2 * (int32_t)st->r1 + (int32_t)st->r2;   /* 0..4092 */
    int64_t acc = (int64_t)p->g * (s << REFLEX_SIG_Q);
    acc -= (int64_t)p->a1 * st->y1;
    acc -= (int64_t)p->a2 * st->y2;
    int32_t y = (int32_t)((acc + ROUND_HALF) >> REFLEX_COEF_Q);
    st->r2 = st->r1;
    st->r1 = r;
    st->y2 = st->y1;
    st->y1 = y;
    return y;
}

/* Send-on-delta with optional DATH, docs/method.md 1.2, in Q16 counts. */
static uint8_t encode(struct reflex_state *st, const struct reflex_params *p, int32_t x)
{
    int32_t d = x - st->prev;
    int32_t mag;
    uint8_t y;
    st->acc += d;
    mag = st->acc < 0 ? -st->acc : st->acc;
    y = mag > st->theta;
    if (y)
        st->acc = 0;
    if (p->dath) {
        if (st->remaining > 0) {            /* active: a spike does not re-arm it */
            if (--st->remaining == 0)
                st->theta = p->theta0;
        } else if (y) {                     /* theta = max(|x_k - x_(k-1)|, floor) */
            int32_t ad = d < 0 ? -d : d;
            st->theta = ad > p->dath_floor ? ad : p->dath_floor;
            st->remaining = p->dath_samples;
        }
    }
    st->prev = x;
    return y;
}

/* Monotonic PI on one window's spike count, docs/method.md 1.4. */
static int16_t mpi(struct reflex_state *st, const struct reflex_params *p, uint8_t v,
                   const int16_t *position)
{
    uint32_t h = (uint32_t)st->h + v;
    int32_t pi, m;
    if (h > REFLEX_H_MAX)
        h = REFLEX_H_MAX;
    st->h = (uint16_t)h;
    pi = (int32_t)st->P0 + (int32_t)p->kp * v + (int32_t)p->ki * (int32_t)h;
    m = pi > st->m ? pi : st->m;
    if (m < p->lo)
        m = p->lo;
    else if (m > p->hi)
        m = p->hi;
    st->m = (int16_t)m;
    if (v == 0) {
        if (++st->zeros == p->reset_after) {
            st->P0 = position ? *position : st->m;
            st->h = 0;
            st->zeros = 0;
        }
    } else {
        st->zeros = 0;
    }
    return st->m;
}

uint8_t reflex_step(struct reflex_state *st, const struct reflex_params *p, uint16_t adc,
                    const int16_t *position, struct reflex_out *out)
{
    uint8_t fault = adc > REFLEX_ADC_MAX || adc < p->adc_min || adc > p->adc_max;
    if (adc == st->last_adc) {
        if (st->same < 0xFFFFu)
            st->same++;
    } else {
        st->same = 0;
    }
    st->last_adc = adc;
    if (p->stuck_after && st->same >= p->stuck_after)
        fault = 1;

    out->event = 0;
    out->fault = fault;
    if (fault) {
        st->primed = 0;   /* skip the sample; the next good one restarts filter+encoder */
    } else {
        int16_t r = (int16_t)adc;
        if (!st->primed)
            prime(st, p, r);
        st->x = p->filter ? lowpass(st, p, r) : (int32_t)r << REFLEX_SIG_Q;
        out->event = encode(st, p, st->x);
    }

    out->window = 0;
    out->v = 0;
    st->count += out->event;
    if (++st->in_window == p->n) {
        out->window = 1;
        out->v = st->count;
        st->in_window = st->count = 0;
        mpi(st, p, out->v, position);
    }
    out->command = st->m;
    return out->window;
}
