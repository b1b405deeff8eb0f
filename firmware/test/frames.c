/* The firmware's framing (src/tsp.c) built natively, for tests/firmware: each stdin line
 * `E type seq payload_hex` is answered with the encoded frame in hex, each `D frame_hex` (without
 * the delimiter) with `rc type seq payload_hex`. */
#include "tsp.h"

#include <stdio.h>
#include <string.h>

static size_t unhex(const char *s, uint8_t *out)
{
    size_t n = 0;
    unsigned b;
    while (sscanf(s, "%2x", &b) == 1) {
        out[n++] = (uint8_t)b;
        s += 2;
    }
    return n;
}

static void hex(const uint8_t *p, size_t n)
{
    for (size_t i = 0; i < n; i++)
        printf("%02x", p[i]);
}

int main(void)
{
    char line[1200];
    uint8_t in[600], out[600];
    while (fgets(line, sizeof line, stdin)) {
        unsigned type, seq;
        char data[1100] = "";
        if (line[0] == 'E' && sscanf(line, "E %u %u %1099s", &type, &seq, data) >= 2) {
            size_t n = unhex(data, in);
            size_t m = tsp_encode((uint8_t)type, (uint16_t)seq, in, n, out);
            hex(out, m);
        } else if (line[0] == 'D' && sscanf(line, "D %1099s", data) == 1) {
            size_t n = unhex(data, in);
            uint8_t t = 0;
            uint16_t s = 0;
            const uint8_t *p = in;
            size_t len = 0;
            int rc = tsp_decode(in, n, &t, &s, &p, &len);
            printf("%d %u %u ", rc, t, s);
            hex(p, rc == 0 ? len : 0);
        }
        printf("\n");
        fflush(stdout);
    }
    return 0;
}
