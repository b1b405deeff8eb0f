/* TSP/1 framing: CRC-16/MCRF4XX, COBS (Cheshire & Baker 1999), frame encode and decode. */
#include "tsp.h"

#include <string.h>

uint16_t tsp_crc(uint16_t crc, const uint8_t *p, size_t n)
{
    /* Bitwise reflected CRC: the 512-byte table of the host would not fit the AVR's RAM. */
    while (n--) {
        crc ^= *p++;
        for (uint8_t b = 0; b < 8; b++)
            crc = (crc & 1) ? (uint16_t)((crc >> 1) ^ 0x8408) : (uint16_t)(crc >> 1);
    }
    return crc;
}

void tsp_put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

void tsp_put_u32(uint8_t *p, uint32_t v)
{
    for (uint8_t i = 0; i < 4; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

void tsp_put_f32(uint8_t *p, float v)
{
    uint32_t u;
    memcpy(&u, &v, 4); /* IEEE-754 binary32 on both avr-gcc and the host */
    tsp_put_u32(p, u);
}

uint16_t tsp_get_u16(const uint8_t *p)
{
    return (uint16_t)(p[0] | ((uint16_t)p[1] << 8));
}

uint32_t tsp_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

/* COBS-encodes one body byte at a time into `out`: `code_at` is where the current block's code
 * byte goes, `code` its running value. */
struct cobs {
    uint8_t *out;
    size_t len;
    size_t code_at;
    uint8_t code;
};

static void cobs_byte(struct cobs *c, uint8_t b)
{
    if (b == 0) {
        c->out[c->code_at] = c->code;
        c->code_at = c->len++;
        c->code = 1;
        return;
    }
    c->out[c->len++] = b;
    if (++c->code == 0xFF) {
        c->out[c->code_at] = c->code;
        c->code_at = c->len++;
        c->code = 1;
    }
}

size_t tsp_encode(uint8_t type, uint16_t seq, const uint8_t *payload, size_t payload_len,
                  uint8_t *out)
{
    if (payload_len + 6 > TSP_MAX_BODY)
        return 0;
    uint8_t head[4] = {TSP_VERSION, type, (uint8_t)seq, (uint8_t)(seq >> 8)};
    uint16_t crc = tsp_crc(0xFFFF, head, 4);
    crc = tsp_crc(crc, payload, payload_len);
    struct cobs c = {out, 1, 0, 1};
    for (uint8_t i = 0; i < 4; i++)
        cobs_byte(&c, head[i]);
    for (size_t i = 0; i < payload_len; i++)
        cobs_byte(&c, payload[i]);
    cobs_byte(&c, (uint8_t)crc);
    cobs_byte(&c, (uint8_t)(crc >> 8));
    out[c.code_at] = c.code;
    out[c.len++] = 0;
    return c.len;
}

int tsp_decode(uint8_t *buf, size_t n, uint8_t *type, uint16_t *seq, const uint8_t **payload,
               size_t *payload_len)
{
    /* COBS decode in place: the output never overtakes the input. */
    size_t r = 0, w = 0;
    while (r < n) {
        uint8_t code = buf[r++];
        if (code == 0 || r + code - 1 > n)
            return -1;
        for (uint8_t i = 1; i < code; i++)
            buf[w++] = buf[r++];
        if (code != 0xFF && r < n)
            buf[w++] = 0;
    }
    if (w < 6)
        return -2;
    uint16_t crc = tsp_crc(0xFFFF, buf, w - 2);
    if (crc != tsp_get_u16(buf + w - 2))
        return -3;
    *type = buf[1];
    *seq = tsp_get_u16(buf + 2);
    *payload = buf + 4;
    *payload_len = w - 6;
    return buf[0] == TSP_VERSION ? 0 : -4;
}
