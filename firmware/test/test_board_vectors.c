/*
 * test_board_vectors.c -- the firmware's reflex core (firmware/reflex/reflex.c) against
 * the shared vectors written by the Python twin (tests/data/board/vectors.txt).
 *
 *   build/test_board_vectors VECTORS.txt
 *
 * For every vector: build struct reflex_params from the P line, feed the I readings to
 * reflex_step (with the Q position at each window's completing sample), and compare
 * every filtered sample (X), event or fault (E), window count and command (W).
 * Prints one FAIL line per mismatching vector (first difference) and a summary;
 * exit status 0 when everything matches, 1 on a mismatch, 2 on a malformed file.
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "reflex.h"

static char *line_of(FILE *f, char kind, char **buf, size_t *cap, long *lineno)
{
    for (;;) {
        ssize_t n = getline(buf, cap, f);
        if (n < 0)
            return NULL;
        ++*lineno;
        if (n && (*buf)[n - 1] == '\n')
            (*buf)[n - 1] = '\0';
        if ((*buf)[0] == '#' || (*buf)[0] == '\0')
            continue;
        if ((*buf)[0] != kind || (*buf)[1] != ' ') {
            fprintf(stderr, "line %ld: expected a '%c' record\n", *lineno, kind);
            exit(2);
        }
        return *buf + 2;
    }
}

/* Comma-separated integers ('-' = empty; '-' inside a list = missing, stored as MISSING). */
#define MISSING (-(1LL << 62))
static long long *parse_list(const char *s, size_t *n)
{
    size_t cap = 16;
    long long *v = malloc(cap * sizeof *v);
    *n = 0;
    if (!strcmp(s, "-"))
        return v;
    while (*s) {
        if (*n == cap)
            v = realloc(v, (cap *= 2) * sizeof *v);
        if (*s == '-' && (s[1] == ',' || s[1] == '\0')) {
            v[(*n)++] = MISSING;
            s++;
        } else {
            char *end;
            v[(*n)++] = strtoll(s, &end, 10);
            s = end;
        }
        if (*s == ',')
            s++;
    }
    return v;
}

static int parse_params(char *s, struct reflex_params *p)
{
    static const char *keys[] = {"g", "a1", "a2", "theta0", "filter", "dath", "dath_samples",
                                 "dath_floor", "x0", "n", "p0", "kp", "ki", "reset_after", "lo",
                                 "hi", "adc_min", "adc_max", "stuck_after"};
    int seen = 0;
    memset(p, 0, sizeof *p);
    for (char *tok = strtok(s, " "); tok; tok = strtok(NULL, " ")) {
        char *eq = strchr(tok, '=');
        if (!eq)
            return -1;
        *eq = '\0';
        const char *val = eq + 1;
        long long x = strcmp(val, "-") ? strtoll(val, NULL, 10) : 0;
        int k;
        for (k = 0; k < 19 && strcmp(tok, keys[k]); k++) {}
        switch (k) {
        case 0: p->g = (int32_t)x; break;
        case 1: p->a1 = (int32_t)x; break;
        case 2: p->a2 = (int32_t)x; break;
        case 3: p->theta0 = (int32_t)x; break;
        case 4: p->filter = (uint8_t)x; break;
        case 5: p->dath = (uint8_t)x; break;
        case 6: p->dath_samples = (uint8_t)x; break;
        case 7: p->dath_floor = (int32_t)x; break;
        case 8: p->x0_given = strcmp(val, "-") != 0; p->x0 = (int32_t)x; break;
        case 9: p->n = (uint8_t)x; break;
        case 10: p->p0 = (int16_t)x; break;
        case 11: p->kp = (uint8_t)x; break;
        case 12: p->ki = (uint8_t)x; break;
        case 13: p->reset_after = (uint8_t)x; break;
        case 14: p->lo = (int16_t)x; break;
        case 15: p->hi = (int16_t)x; break;
        case 16: p->adc_min = (uint16_t)x; break;
        case 17: p->adc_max = (uint16_t)x; break;
        case 18: p->stuck_after = (uint16_t)x; break;
        default: return -1;
        }
        seen |= 1 << k;
    }
    return seen == (1 << 19) - 1 ? 0 : -1;
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
    char *buf = NULL, name[256];
    size_t cap = 0;
    long lineno = 0, samples = 0;
    int vectors = 0, failures = 0;
    char *s;
    while ((s = line_of(f, 'V', &buf, &cap, &lineno)) != NULL) {
        snprintf(name, sizeof name, "%s", s);
        struct reflex_params p;
        if (parse_params(line_of(f, 'P', &buf, &cap, &lineno), &p) != 0) {
            fprintf(stderr, "line %ld: bad parameters in vector %s\n", lineno, name);
            return 2;
        }
        size_t ni, nq, nx, nw;
        long long *adc = parse_list(line_of(f, 'I', &buf, &cap, &lineno), &ni);
        long long *pos = parse_list(line_of(f, 'Q', &buf, &cap, &lineno), &nq);
        long long *x = parse_list(line_of(f, 'X', &buf, &cap, &lineno), &nx);
        char *ev = strdup(line_of(f, 'E', &buf, &cap, &lineno));
        char *wl = line_of(f, 'W', &buf, &cap, &lineno);
        if (!wl || nx != ni || (strcmp(ev, "-") ? strlen(ev) : 0) != ni) {
            fprintf(stderr, "line %ld: vector %s is incomplete\n", lineno, name);
            return 2;
        }
        /* W items are v:command; reuse parse_list on a copy with ':' as ','. */
        for (char *c = wl; *c; c++)
            if (*c == ':')
                *c = ',';
        long long *w = parse_list(wl, &nw);

        struct reflex_state st;
        struct reflex_out out;
        reflex_init(&st, &p);
        size_t z = 0;
        int bad = 0;
        for (size_t k = 0; k < ni && !bad; k++) {
            int16_t position = 0;
            const int16_t *pp = NULL;
            if (z < nq && pos[z] != MISSING) {
                position = (int16_t)pos[z];
                pp = &position;
            }
            reflex_step(&st, &p, (uint16_t)adc[k], pp, &out);
            char e = out.fault ? 'f' : out.event ? '1' : '0';
            if (st.x != x[k] || e != ev[k]) {
                printf("FAIL %s sample %zu: x %ld event %c, expected x %lld event %c\n", name, k,
                       (long)st.x, e, x[k], ev[k]);
                bad = 1;
            } else if (out.window) {
                if (2 * z + 1 >= nw || out.v != w[2 * z] || out.command != w[2 * z + 1]) {
                    printf("FAIL %s window %zu: v %u command %d, expected %s\n", name, z,
                           out.v, out.command, 2 * z + 1 < nw ? "another" : "no window");
                    bad = 1;
                }
                z++;
            }
        }
        if (!bad && 2 * z != nw) {
            printf("FAIL %s: %zu windows, expected %zu\n", name, z, nw / 2);
            bad = 1;
        }
        failures += bad;
        vectors++;
        samples += (long)ni;
        free(adc); free(pos); free(x); free(w); free(ev);
    }
    free(buf);
    fclose(f);
    printf("%d vectors, %ld samples checked, %d failures\n", vectors, samples, failures);
    return failures ? 1 : 0;
}
