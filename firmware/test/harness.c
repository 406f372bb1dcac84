/*
 * harness.c -- runs the DAQ firmware under simavr with simulated peripherals.
 *
 *   build/harness FIRMWARE.elf OUTDIR SECONDS [--no-imu | --imu-from S] [--flow-hz HZ]
 *                 [--seed N] [--profile] [--mcu atmega328p|atmega2560] [--adc FILE]
 *
 * Simulated around an ATmega328P (or --mcu atmega2560) at 16 MHz, AVcc = 5 V:
 *   - slip sensor on ADC0: at every conversion start a new pseudo-random count 0..1023
 *     is injected (as the millivolts that simavr converts back to exactly that count);
 *     with --adc FILE the counts come from FILE (whitespace-separated integers 0..1023),
 *     the last one repeated when the file runs out;
 *   - YF-S201 on PD2/INT0 (PE4/INT4 on the ATmega2560): a square wave at --flow-hz
 *     (default 97 Hz);
 *   - MPU6050 at I2C address 0x68 on the TWI bus: registers, auto-increment, sleep bit
 *     (power-on value of PWR_MGMT_1 is 0x40: asleep, readings frozen at 0 until the
 *     firmware wakes it). Every burst read starting at ACCEL_XOUT_H latches a new
 *     pseudo-random reading. --no-imu leaves the bus empty (every address NACKed);
 *     --imu-from S plugs a powered-on (asleep) MPU6050 in at S simulated seconds.
 *   - --stall-at S: at S simulated seconds the sample clock stops (OCIE1A cleared in
 *     TIMSK1, as a hung interrupt would leave it): no conversion, no sample, nothing
 *     feeds the watchdog, which resets the firmware 60 ms later (logged as "R <cycle>");
 *   - UART0 captured byte by byte with the CPU cycle at which the firmware wrote UDR0;
 *     on the ATmega2560 UART1 too (the i-Limb hand), into uart1.bin / uart1_cycles.bin.
 *
 * Writes OUTDIR/uart.bin (the bytes), OUTDIR/uart_cycles.bin (uint64 little-endian
 * cycle per byte) and OUTDIR/events.txt, one event per line:
 *   A <cycle> <count> <busy>   ADC conversion started on channel <count>'s input;
 *                              <busy> = CPU cycles not spent asleep so far
 *   P <cycle>                  flow-sensor falling edge (one pulse)
 *   I <cycle> <ax> <ay> <az>   the MPU6050 latched this reading for a burst read
 *   W <cycle> <reg> <value>    the firmware wrote an MPU6050 register
 *   E <cycle> <text>           something the firmware must never do (e.g. wrong ADC channel)
 *   S <cycle>                  --stall-at: the sample clock was stopped
 *   R <cycle>                  the firmware restarted (program counter back at 0)
 *   X <cycles> <sleep_cycles>  end of run
 * With --profile, also OUTDIR/profile.txt: "<pc> <cycles>" per flash byte address, the
 * awake CPU cycles spent on the instruction there (benchmarks/firmware_budget.py maps
 * them to functions).
 * The checker is firmware/test/check_capture.py.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "avr_adc.h"
#include "avr_ioport.h"
#include "avr_twi.h"
#include "avr_uart.h"
#include "sim_avr.h"
#include "sim_cycle_timers.h"
#include "sim_elf.h"

#define F_CPU_HZ 16000000u
#define VREF_MV 5000u
#define MPU_ADDR 0x68u
#define MPU_PWR_MGMT_1 0x6Bu
#define MPU_ACCEL_XOUT_H 0x3Bu

static avr_t *avr;
static FILE *events;
struct capture {
    uint8_t *bytes;
    uint64_t *cycles;
    size_t n, cap;
};
static struct capture uart[2];
static uint64_t sleep_cycles;
static uint64_t rng_state = 0x9E3779B97F4A7C15ull;

static uint32_t rng(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (uint32_t)(rng_state >> 33);
}

/* ---- sleeping: count it, never wait in real time ------------------------------ */
static void count_sleep(avr_t *a, avr_cycle_count_t how_long)
{
    (void)a;
    sleep_cycles += 1 + how_long;   /* what avr_callback_run_raw adds to avr->cycle */
}

static uint64_t busy_cycles(void) { return avr->cycle - sleep_cycles; }

/* ---- UART capture ---------------------------------------------------------------- */
static void uart_out(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    struct capture *c = param;
    if (c->n == c->cap) {
        c->cap = c->cap ? 2 * c->cap : 1 << 16;
        c->bytes = realloc(c->bytes, c->cap);
        c->cycles = realloc(c->cycles, c->cap * sizeof *c->cycles);
        if (!c->bytes || !c->cycles) { perror("realloc"); exit(2); }
    }
    c->bytes[c->n] = (uint8_t)value;
    c->cycles[c->n++] = avr->cycle;
}

/* ---- ADC: inject a new count at every conversion start --------------------------- */
static avr_irq_t *adc0_irq;
static uint32_t *adc_file;          /* --adc: counts to inject, in order */
static size_t adc_file_n, adc_file_i;

static void adc_trigger(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq; (void)param;
    union { avr_adc_mux_t mux; uint32_t v; } m = { .v = value };
    if (m.mux.kind != ADC_MUX_SINGLE || m.mux.src != 0)
        fprintf(events, "E %llu adc-mux kind=%u src=%u\n", (unsigned long long)avr->cycle,
                (unsigned)m.mux.kind, (unsigned)m.mux.src);
    uint32_t count;
    if (adc_file)
        count = adc_file[adc_file_i < adc_file_n ? adc_file_i++ : adc_file_n - 1];
    else
        count = rng() % 1024u;
    /* simavr converts as floor(mV * 1023 / Vref): pick the smallest mV giving count. */
    uint32_t mv = (count * VREF_MV + 1022u) / 1023u;
    if (mv * 1023u / VREF_MV != count) { fprintf(stderr, "adc inversion\n"); exit(2); }
    avr_raise_irq(adc0_irq, mv);
    fprintf(events, "A %llu %u %llu\n", (unsigned long long)avr->cycle, count,
            (unsigned long long)busy_cycles());
}

/* ---- flow sensor: square wave on PD2 -------------------------------------------- */
static avr_irq_t *flow_irq;
static double flow_half_period, flow_next;
static int flow_level = 1;

static avr_cycle_count_t flow_timer(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)param;
    flow_level = !flow_level;
    avr_raise_irq(flow_irq, (uint32_t)flow_level);
    if (!flow_level)
        fprintf(events, "P %llu\n", (unsigned long long)a->cycle);
    flow_next += flow_half_period;
    avr_cycle_count_t next = (avr_cycle_count_t)flow_next;
    return next > when ? next : when + 1;
}

/* ---- MPU6050 on the TWI bus ------------------------------------------------------ */
static struct {
    int present;
    avr_irq_t *irq;        /* [0] to the AVR (TWI input), [1] from the AVR */
    uint8_t regs[128];
    uint8_t ptr;
    int selected, index;
} mpu;

static void mpu_reply(uint8_t msg, uint8_t data)
{
    avr_raise_irq(mpu.irq + TWI_IRQ_INPUT, avr_twi_irq_msg(msg, MPU_ADDR << 1, data));
}

static void mpu_latch(void)
{
    if (mpu.regs[MPU_PWR_MGMT_1] & 0x40u)      /* asleep: the data registers freeze */
        return;
    int16_t v[3];
    for (int i = 0; i < 3; i++) {
        v[i] = (int16_t)(uint16_t)rng();
        mpu.regs[MPU_ACCEL_XOUT_H + 2 * i] = (uint8_t)((uint16_t)v[i] >> 8);
        mpu.regs[MPU_ACCEL_XOUT_H + 2 * i + 1] = (uint8_t)v[i];
    }
    fprintf(events, "I %llu %d %d %d\n", (unsigned long long)avr->cycle, v[0], v[1], v[2]);
}

static void mpu_from_avr(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq; (void)param;
    avr_twi_msg_irq_t m;
    m.u.v = value;
    if (m.u.twi.msg & TWI_COND_STOP)
        mpu.selected = 0;
    if (m.u.twi.msg & TWI_COND_START) {
        mpu.selected = 0;
        mpu.index = 0;
        if (mpu.present && (m.u.twi.addr >> 1) == MPU_ADDR) {
            mpu.selected = 1;
            mpu_reply(TWI_COND_ACK, 1);
        }
    }
    if (!mpu.selected)
        return;
    if (m.u.twi.msg & TWI_COND_WRITE) {
        mpu_reply(TWI_COND_ACK, 1);
        if (mpu.index++ == 0) {
            mpu.ptr = m.u.twi.data & 0x7Fu;
            if (mpu.ptr == MPU_ACCEL_XOUT_H)
                mpu_latch();
        } else {
            fprintf(events, "W %llu %u %u\n", (unsigned long long)avr->cycle, mpu.ptr,
                    m.u.twi.data);
            mpu.regs[mpu.ptr] = m.u.twi.data;
            mpu.ptr = (mpu.ptr + 1u) & 0x7Fu;
        }
    }
    if (m.u.twi.msg & TWI_COND_READ) {
        mpu_reply(TWI_COND_READ, mpu.regs[mpu.ptr]);
        mpu.ptr = (mpu.ptr + 1u) & 0x7Fu;
    }
}

/* ---- --stall-at: stop the sample clock, as a hung interrupt handler would ----------- */
#define TIMSK1_ADDR 0x6Fu           /* TIMSK1's data address on the ATmega328P and 2560 */
#define OCIE1A_BIT 1u
static avr_cycle_count_t stall(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)when; (void)param;
    a->data[TIMSK1_ADDR] &= (uint8_t)~(1u << OCIE1A_BIT);
    fprintf(events, "S %llu\n", (unsigned long long)a->cycle);
    return 0;
}

static avr_cycle_count_t mpu_plug_in(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)a; (void)when; (void)param;
    mpu.present = 1;
    return 0;
}

/* ---- main ------------------------------------------------------------------------ */
static void write_file(const char *dir, const char *name, const void *data, size_t n)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(data, 1, n, f) != n || fclose(f) != 0) { perror(path); exit(2); }
}

static void read_adc_file(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) { perror(path); exit(2); }
    size_t cap = 1024;
    long v;
    adc_file = malloc(cap * sizeof *adc_file);
    while (fscanf(f, "%ld", &v) == 1) {
        if (v < 0 || v > 1023) { fprintf(stderr, "%s: count %ld out of 0..1023\n", path, v); exit(2); }
        if (adc_file_n == cap)
            adc_file = realloc(adc_file, (cap *= 2) * sizeof *adc_file);
        adc_file[adc_file_n++] = (uint32_t)v;
    }
    if (!feof(f) || adc_file_n == 0) { fprintf(stderr, "%s: expected integers 0..1023\n", path); exit(2); }
    fclose(f);
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: %s FIRMWARE.elf OUTDIR SECONDS [--no-imu | --imu-from S] "
                        "[--flow-hz HZ] [--seed N] [--profile] [--mcu M] [--adc FILE] [--stall-at S]\n", argv[0]);
        return 2;
    }
    const char *elf = argv[1], *outdir = argv[2], *mcu = "atmega328p";
    double seconds = atof(argv[3]), flow_hz = 97.0, imu_from = 0.0, stall_at = 0.0;
    int profile = 0;
    mpu.present = 1;
    for (int i = 4; i < argc; i++) {
        if (!strcmp(argv[i], "--no-imu")) mpu.present = 0;
        else if (!strcmp(argv[i], "--profile")) profile = 1;
        else if (!strcmp(argv[i], "--imu-from") && i + 1 < argc) imu_from = atof(argv[++i]);
        else if (!strcmp(argv[i], "--flow-hz") && i + 1 < argc) flow_hz = atof(argv[++i]);
        else if (!strcmp(argv[i], "--stall-at") && i + 1 < argc) stall_at = atof(argv[++i]);
        else if (!strcmp(argv[i], "--mcu") && i + 1 < argc) mcu = argv[++i];
        else if (!strcmp(argv[i], "--adc") && i + 1 < argc) read_adc_file(argv[++i]);
        else if (!strcmp(argv[i], "--seed") && i + 1 < argc)
            rng_state ^= strtoull(argv[++i], NULL, 0) * 0xD1B54A32D192ED03ull;
        else { fprintf(stderr, "unknown option %s\n", argv[i]); return 2; }
    }
    if (seconds <= 0 || flow_hz <= 0) { fprintf(stderr, "bad SECONDS or --flow-hz\n"); return 2; }

    elf_firmware_t fw;
    memset(&fw, 0, sizeof fw);
    if (elf_read_firmware(elf, &fw) != 0) { fprintf(stderr, "cannot read %s\n", elf); return 2; }
    int mega = !strcmp(mcu, "atmega2560");
    if (!mega && strcmp(mcu, "atmega328p")) { fprintf(stderr, "unknown --mcu %s\n", mcu); return 2; }
    snprintf(fw.mmcu, sizeof fw.mmcu, "%s", mcu);
    fw.frequency = F_CPU_HZ;
    avr = avr_make_mcu_by_name(fw.mmcu);
    if (!avr) { fprintf(stderr, "simavr has no %s\n", mcu); return 2; }
    avr_init(avr);
    avr_load_firmware(avr, &fw);
    avr->vcc = avr->avcc = avr->aref = VREF_MV;
    avr->sleep = count_sleep;
    avr->log = LOG_ERROR;

    char path[4096];
    snprintf(path, sizeof path, "%s/events.txt", outdir);
    events = fopen(path, "w");
    if (!events) { perror(path); return 2; }

    for (int u = 0; u < 1 + mega; u++) {
        char name = (char)('0' + u);
        uint32_t flags = 0;
        avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS(name), &flags);
        flags &= ~AVR_UART_FLAG_STDIO;
        avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS(name), &flags);
        avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ(name), UART_IRQ_OUTPUT),
                                uart_out, &uart[u]);
    }

    adc0_irq = avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_OUT_TRIGGER),
                            adc_trigger, NULL);

    flow_irq = mega ? avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('E'), IOPORT_IRQ_PIN4)
                    : avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), IOPORT_IRQ_PIN2);
    avr_raise_irq(flow_irq, 1);
    flow_half_period = F_CPU_HZ / (2.0 * flow_hz);
    flow_next = 1000.0 + flow_half_period;   /* first edge after reset settles */
    avr_cycle_timer_register(avr, (avr_cycle_count_t)flow_next, flow_timer, NULL);

    static const char *names[2] = {"8>mpu.out", "32<mpu.in"};
    mpu.irq = avr_alloc_irq(&avr->irq_pool, 0, 2, names);
    mpu.regs[MPU_PWR_MGMT_1] = 0x40u;        /* power-on: sleep */
    mpu.regs[0x75] = MPU_ADDR;               /* WHO_AM_I */
    if (imu_from > 0) {
        mpu.present = 0;
        avr_cycle_timer_register(avr, (avr_cycle_count_t)(imu_from * F_CPU_HZ), mpu_plug_in,
                                 NULL);
    }
    avr_connect_irq(mpu.irq + TWI_IRQ_INPUT, avr_io_getirq(avr, AVR_IOCTL_TWI_GETIRQ(0),
                                                           TWI_IRQ_INPUT));
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_TWI_GETIRQ(0), TWI_IRQ_OUTPUT),
                            mpu_from_avr, NULL);

    if (stall_at > 0)
        avr_cycle_timer_register(avr, (avr_cycle_count_t)(stall_at * F_CPU_HZ), stall, NULL);

    const uint64_t end = (uint64_t)(seconds * F_CPU_HZ);
    int state = cpu_Running;
    static uint64_t pc_cycles[262144];
    while (avr->cycle < end) {
        if (profile) {
            uint32_t pc = avr->pc;
            uint64_t c0 = avr->cycle, s0 = sleep_cycles;
            state = avr_run(avr);
            if (pc < sizeof pc_cycles / sizeof pc_cycles[0])
                pc_cycles[pc] += (avr->cycle - c0) - (sleep_cycles - s0);
        } else {
            state = avr_run(avr);
        }
        if (avr->pc == 0 && avr->cycle > 0)
            fprintf(events, "R %llu\n", (unsigned long long)avr->cycle);
        if (state == cpu_Done || state == cpu_Crashed)
            break;
    }
    if (profile) {
        snprintf(path, sizeof path, "%s/profile.txt", outdir);
        FILE *pf = fopen(path, "w");
        if (!pf) { perror(path); return 2; }
        for (size_t pc = 0; pc < sizeof pc_cycles / sizeof pc_cycles[0]; pc++)
            if (pc_cycles[pc])
                fprintf(pf, "%zu %llu\n", pc, (unsigned long long)pc_cycles[pc]);
        fclose(pf);
    }
    fprintf(events, "X %llu %llu\n", (unsigned long long)avr->cycle,
            (unsigned long long)sleep_cycles);
    fclose(events);
    write_file(outdir, "uart.bin", uart[0].bytes, uart[0].n);
    write_file(outdir, "uart_cycles.bin", uart[0].cycles, uart[0].n * sizeof *uart[0].cycles);
    if (mega) {
        write_file(outdir, "uart1.bin", uart[1].bytes, uart[1].n);
        write_file(outdir, "uart1_cycles.bin", uart[1].cycles, uart[1].n * sizeof *uart[1].cycles);
    }
    printf("harness: %.3f s simulated, %zu UART bytes, CPU busy %.2f%% of cycles%s\n",
           (double)avr->cycle / F_CPU_HZ, uart[0].n,
           100.0 * (double)(avr->cycle - sleep_cycles) / (double)avr->cycle,
           (state == cpu_Done || state == cpu_Crashed) ? ", FIRMWARE STOPPED" : "");
    return (state == cpu_Done || state == cpu_Crashed) ? 1 : 0;
}
