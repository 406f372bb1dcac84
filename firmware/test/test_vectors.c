/*
 * test_vectors.c -- host-side check of the firmware's frame encoder and CRC against
 * the shared vectors file (tests/data/wire/vectors.txt; format in docs/wire-protocol.md).
 *
 *   build/test_vectors ../tests/data/wire/vectors.txt
 *
 * F records: encode the decoded fields with wire_encode() and compare the bytes;
 * R records (version 2): the same with wire_encode_reflex().
 * B records: a small reference decoder must reject the bytes for the stated reason.
 * S records (parser streams) are Python-only and are counted, not checked.
 * Prints one line per failure and a summary; exit status 0 only if all pass.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "wire.h"

#define MAX_BYTES 512

static int hexval(int c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* Parse a hex token ("-" = empty) into out; return the length or -1. */
static int parse_hex(const char *tok, uint8_t *out)
{
    if (strcmp(tok, "-") == 0) return 0;
    size_t n = strlen(tok);
    if (n % 2 || n / 2 > MAX_BYTES) return -1;
    for (size_t i = 0; i < n / 2; i++) {
        int hi = hexval(tok[2 * i]), lo = hexval(tok[2 * i + 1]);
        if (hi < 0 || lo < 0) return -1;
        out[i] = (uint8_t)(hi << 4 | lo);
    }
    return (int)(n / 2);
}

/* Reference verdict for one candidate frame. */
static const char *verdict(const uint8_t *b, int len)
{
    /* The version byte gives the length; an unknown version is checked as version 1. */
    int want = (len > 2 && b[0] == WIRE_SYNC0 && b[1] == WIRE_SYNC1
                && b[2] == WIRE_VERSION_REFLEX) ? (int)WIRE_FRAME_LEN_REFLEX : (int)WIRE_FRAME_LEN;
    if (len != want) return "truncated";
    if (b[0] != WIRE_SYNC0 || b[1] != WIRE_SYNC1) return "sync";
    if (wire_crc16(0xFFFFu, b + 2, (uint8_t)(want - 2)) != 0) return "crc";
    if (b[2] != WIRE_VERSION && b[2] != WIRE_VERSION_REFLEX) return "version";
    if ((unsigned)(b[6] | b[7] << 8) > WIRE_ADC_MAX) return "adc";
    return "ok";
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s VECTORS.txt\n", argv[0]);
        return 2;
    }
    FILE *f = fopen(argv[1], "r");
    if (!f) {
        perror(argv[1]);
        return 2;
    }
    int fails = 0, nf = 0, nb = 0, ns = 0, lineno = 0;
    for (unsigned i = 0; i < 256; i++) {      /* the table against the bitwise definition */
        uint16_t c = (uint16_t)(i << 8);
        for (int b = 0; b < 8; b++)
            c = (c & 0x8000u) ? (uint16_t)((c << 1) ^ 0x1021u) : (uint16_t)(c << 1);
        if (wire_crc_table[i] != c) {
            printf("FAIL wire_crc_table[%u] = %04x, expected %04x\n", i, wire_crc_table[i], c);
            fails++;
        }
    }
    static const uint8_t check[] = "123456789";
    if (wire_crc16(0xFFFFu, check, 9) != 0x29B1u) {
        printf("FAIL crc check value %04x != 29b1\n", wire_crc16(0xFFFFu, check, 9));
        fails++;
    }
    char line[4096];
    while (fgets(line, sizeof line, f)) {
        lineno++;
        if (line[0] == '#' || line[0] == '\n') continue;
        char kind, name[128], hex[2 * MAX_BYTES + 2], rest[1024];
        uint8_t bytes[MAX_BYTES];
        if (sscanf(line, "%c %127s %1025s %1023[^\n]", &kind, name, hex, rest) < 3) {
            printf("FAIL line %d: cannot parse\n", lineno);
            fails++;
            continue;
        }
        int len = parse_hex(hex, bytes);
        if (len < 0) {
            printf("FAIL line %d (%s): bad hex\n", lineno, name);
            fails++;
            continue;
        }
        if (kind == 'F' || kind == 'R') {
            long seq, flags, adc, ax, ay, az, bits = 0, v = 0, command = 0, x = 0;
            unsigned long flow;
            int want = kind == 'F' ? 7 : 11;
            nf++;
            if (sscanf(rest, "%ld %ld %ld %ld %ld %ld %lu %ld %ld %ld %ld", &seq, &flags, &adc,
                       &ax, &ay, &az, &flow, &bits, &v, &command, &x) != want) {
                printf("FAIL line %d (%s): bad fields\n", lineno, name);
                fails++;
                continue;
            }
            struct wire_sample s = {
                .seq = (uint16_t)seq, .flags = (uint8_t)flags, .adc = (uint16_t)adc,
                .accel = {(int16_t)ax, (int16_t)ay, (int16_t)az}, .flow = (uint32_t)flow,
            };
            uint8_t out[WIRE_FRAME_LEN_REFLEX];
            unsigned n = WIRE_FRAME_LEN;
            if (kind == 'F') {
                wire_encode(out, &s);
            } else {
                struct wire_reflex r = {.bits = (uint8_t)bits, .v = (uint8_t)v,
                                        .command = (int16_t)command, .x = (int32_t)x};
                wire_encode_reflex(out, &s, &r);
                n = WIRE_FRAME_LEN_REFLEX;
            }
            if (len != (int)n || memcmp(out, bytes, n) != 0) {
                printf("FAIL %c %s: encoder gives ", kind, name);
                for (unsigned i = 0; i < n; i++) printf("%02x", out[i]);
                printf(", vector has %s\n", hex);
                fails++;
            } else if (strcmp(verdict(bytes, len), "ok") != 0) {
                printf("FAIL F %s: decoder says %s\n", name, verdict(bytes, len));
                fails++;
            }
        } else if (kind == 'B') {
            char reason[32];
            nb++;
            if (sscanf(rest, "%31s", reason) != 1 || strcmp(verdict(bytes, len), reason) != 0) {
                printf("FAIL B %s: expected %s, decoder says %s\n", name, rest,
                       verdict(bytes, len));
                fails++;
            }
        } else if (kind == 'S') {
            ns++;
        } else {
            printf("FAIL line %d: unknown record kind '%c'\n", lineno, kind);
            fails++;
        }
    }
    fclose(f);
    printf("test_vectors: %d good frames, %d bad frames checked, %d streams skipped, %d failures\n",
           nf, nb, ns, fails);
    return (fails || nf == 0 || nb == 0) ? 1 : 0;
}
