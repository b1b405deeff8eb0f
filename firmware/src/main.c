/* propid reference firmware for an ATmega328P hobby stand: HX711 load cells, ESC by servo PWM
 * from Timer1, rpm on INT0, voltage and current on the ADC, TSP/1 (or the CSV fallback) on the
 * UART. The device side of docs/PROTOCOL.md §3–4; crates/sim/src/firmware.rs is its model in
 * Rust and both behave alike (sample timing, command results, duplicates, watchdog).
 *
 * Safety: the ESC gets ESC_MIN_US from boot; STOP, DISARM, `!`, the protocol watchdog
 * (`watchdog_ms` without a valid command while armed) and a storm of framing errors put it back
 * to ESC_MIN_US at once and disarm; the AVR's own watchdog resets a hung loop (and a reset
 * leaves the pin low, then ESC_MIN_US). Nothing re-arms by itself. */
#include "config.h"
#include "tsp.h"

#include <avr/eeprom.h>
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <avr/wdt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <util/atomic.h>
#include <util/delay.h>

#define ARM_KEY 0x214D5241UL
#define THROTTLE_FULL 10000
#define MAX_IMPULSE_US 1000000UL

/* Sample flags (PROTOCOL.md §3). */
#define F_ARMED (1u << 0)
#define F_THRUST_VALID (1u << 1)
#define F_TORQUE_VALID (1u << 2)
#define F_RPM_VALID (1u << 3)
#define F_VOLTAGE_VALID (1u << 4)
#define F_CURRENT_VALID (1u << 5)
#define F_IMPULSE_ACTIVE (1u << 6)
#define F_RAMP_ACTIVE (1u << 7)
#define F_WATCHDOG_TRIPPED (1u << 8)
#define F_THRUST_FRESH (1u << 10)
#define F_RPM_FRESH (1u << 11)

/* Event codes. */
enum { EV_IMPULSE_START = 1, EV_IMPULSE_END, EV_WATCHDOG_TRIP, EV_LIMIT_CUTOFF, EV_ARMED,
       EV_DISARMED, EV_TX_OVERRUN, EV_RESET_CAUSE, EV_TARE_DONE };

/* ---- reset cause, read before anything else (a WDT reset must not loop) ---- */
uint8_t mcusr_mirror __attribute__((section(".noinit")));
void early_init(void) __attribute__((naked, used, section(".init3")));
void early_init(void)
{
    mcusr_mirror = MCUSR;
    MCUSR = 0;
    wdt_disable();
    DDRB &= ~_BV(PB1); /* the ESC pin stays low (no pulses) until setup */
}

/* ---- time: Timer0 CTC at 1 kHz, 4 us resolution ---- */
static volatile uint32_t ms_count;
ISR(TIMER0_COMPA_vect) { ms_count++; }

static uint32_t micros(void)
{
    uint32_t m;
    uint8_t t, f;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        m = ms_count;
        t = TCNT0;
        f = TIFR0 & _BV(OCF0A);
    }
    if (f && t < 125)
        m++;
    return m * 1000UL + (uint32_t)t * 4;
}

/* ---- UART: interrupt-driven rings ---- */
#define RX_SIZE 128
#define TX_SIZE 512
static volatile uint8_t rx_buf[RX_SIZE];
static volatile uint8_t rx_head, rx_tail;
static volatile uint8_t rx_errors; /* framing and overrun errors, for the storm check */
static volatile uint8_t tx_buf[TX_SIZE];
static volatile uint16_t tx_head, tx_tail;

ISR(USART_RX_vect)
{
    uint8_t st = UCSR0A;
    uint8_t b = UDR0;
    if (st & (_BV(FE0) | _BV(DOR0))) {
        rx_errors++;
        return;
    }
    uint8_t n = (uint8_t)((rx_head + 1) % RX_SIZE);
    if (n != rx_tail) {
        rx_buf[rx_head] = b;
        rx_head = n;
    }
}

ISR(USART_UDRE_vect)
{
    if (tx_head == tx_tail) {
        UCSR0B &= ~_BV(UDRIE0);
        return;
    }
    UDR0 = tx_buf[tx_tail];
    tx_tail = (tx_tail + 1) % TX_SIZE;
}

static uint16_t tx_free(void)
{
    uint16_t h, t;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        h = tx_head;
        t = tx_tail;
    }
    return (uint16_t)((t + TX_SIZE - h - 1) % TX_SIZE);
}

/* Queues `n` bytes whole or not at all. */
static uint8_t tx_write(const uint8_t *p, uint16_t n)
{
    if (tx_free() < n)
        return 0;
    for (uint16_t i = 0; i < n; i++) {
        tx_buf[tx_head] = p[i];
        ATOMIC_BLOCK(ATOMIC_RESTORESTATE) { tx_head = (tx_head + 1) % TX_SIZE; }
    }
    UCSR0B |= _BV(UDRIE0);
    return 1;
}

/* A BAUD of 115200 from 16 MHz is 2.1 % fast with U2X (as on every Arduino Uno): tolerated. */
#define BAUD_TOL 3
static void uart_init(void)
{
#include <util/setbaud.h>
    UBRR0H = UBRRH_VALUE;
    UBRR0L = UBRRL_VALUE;
#if USE_2X
    UCSR0A = _BV(U2X0);
#else
    UCSR0A = 0;
#endif
    UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
    UCSR0B = _BV(RXEN0) | _BV(TXEN0) | _BV(RXCIE0);
}

/* ---- ESC: Timer1 fast PWM (mode 14, TOP = ICR1), 0.5 us ticks on OC1A ---- */
static void esc_write(uint16_t level)
{
    uint32_t us = ESC_MIN_US + (uint32_t)level * (ESC_MAX_US - ESC_MIN_US) / THROTTLE_FULL;
    uint16_t ocr = (uint16_t)(us * 2);
    if (OCR1A == ocr)
        return;
    OCR1A = ocr; /* double-buffered: the chip applies it at the next period */
}

static void esc_init(void)
{
    /* TOP and the first pulse before the clock starts (simavr also reads TOP only then) */
    ICR1 = (uint16_t)(2000000UL / ESC_HZ - 1);
    esc_write(0);
    DDRB |= _BV(PB1);
    TCCR1A = _BV(COM1A1) | _BV(WGM11);
    TCCR1B = _BV(WGM13) | _BV(WGM12) | _BV(CS11);
}

/* ---- rpm: INT0 edge times ---- */
static volatile uint16_t rpm_edges;
static volatile uint32_t rpm_last_us;
ISR(INT0_vect)
{
    rpm_last_us = micros();
    rpm_edges++;
}

/* ---- HX711: 24-bit two's complement, 25 clocks (channel A, gain 128 next) ---- */
static uint8_t hx_ready(uint8_t dout) { return !(HX_PIN & _BV(dout)); }

static int32_t hx_read(uint8_t dout, uint8_t sck)
{
    uint32_t v = 0;
    for (uint8_t i = 0; i < 25; i++) {
        /* SCK high for more than 60 us powers the HX711 down: no interrupt while it is high
         * (interrupts run between bits, so the UART never waits 50 us) */
        ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
        {
            HX_PORT |= _BV(sck);
            _delay_us(1);
            if (i < 24)
                v = (v << 1) | (hx_ready(dout) ? 0 : 1);
            HX_PORT &= ~_BV(sck);
        }
        _delay_us(1);
    }
    if (v & 0x800000UL)
        v |= 0xFF000000UL;
    return (int32_t)v;
}

/* ---- ADC ---- */
static uint16_t adc_read(uint8_t ch)
{
    ADMUX = _BV(REFS0) | (ch & 7);
    ADCSRA = _BV(ADEN) | _BV(ADSC) | _BV(ADPS2) | _BV(ADPS1) | _BV(ADPS0);
    while (ADCSRA & _BV(ADSC))
        ;
    return ADC;
}

/* ---- calibration in EEPROM ---- */
struct calib {
    uint16_t magic;
    int32_t thrust_zero;
    float thrust_counts_per_n;
    int32_t torque_zero;
    float torque_counts_per_nm;
    uint16_t boots;
};
#define CALIB_MAGIC 0x5031
static struct calib EEMEM ee_calib;
static struct calib cal;

static void calib_load(void)
{
    eeprom_read_block(&cal, &ee_calib, sizeof cal);
    if (cal.magic != CALIB_MAGIC) {
        memset(&cal, 0, sizeof cal);
        cal.magic = CALIB_MAGIC;
        cal.thrust_counts_per_n = THRUST_COUNTS_PER_N;
        cal.torque_counts_per_nm = TORQUE_COUNTS_PER_NM;
    }
}

static void calib_save(void) { eeprom_update_block(&cal, &ee_calib, sizeof cal); }

/* ---- device state ---- */
static uint8_t csv_mode;
static uint32_t boot_id;
static uint16_t tx_seq;
static uint16_t rate_hz = DEFAULT_RATE_HZ;
static uint32_t sched_base_us;
static uint16_t sched_k;
static uint32_t next_boundary_us;
static uint32_t index_now; /* index of the period now running */
static uint8_t running;
static uint16_t cur_throttle, cur_flags;
static uint8_t armed, watchdog_tripped;
static uint32_t watchdog_us = 500000UL;
static uint32_t last_cmd_us;
static uint16_t setpoint;
static uint8_t ramp_on;
static uint16_t ramp_from, ramp_to;
static uint32_t ramp_start_us, ramp_dur_us;
enum { PULSE_IDLE, PULSE_PENDING, PULSE_ACTIVE };
static uint8_t pulse_state;
static uint16_t pulse_level;
static uint32_t pulse_left;
static uint32_t next_hello_us;
static int32_t raw_thrust, raw_torque;
static uint8_t have_thrust, have_torque;
static uint16_t rpm_prev_edges;
static uint32_t rpm_prev_us;
static uint8_t rpm_have_prev;
static float rpm_value;
static uint16_t tx_dropped;
static uint8_t storm_count;
static uint32_t storm_start_us;

/* Duplicate detection: the last 8 (seq, type, result) for one second. */
struct dedup {
    uint16_t seq;
    uint8_t type, result, used;
    uint32_t at_us;
};
static struct dedup dedup[8];
static uint8_t dedup_next;

/* ---- output ---- */
static const char *event_name(uint8_t code)
{
    static const char *const names[] = {"IMPULSE_START", "IMPULSE_END", "WATCHDOG_TRIP",
                                        "LIMIT_CUTOFF", "ARMED", "DISARMED", "TX_OVERRUN",
                                        "RESET_CAUSE", "TARE_DONE"};
    return (code >= 1 && code <= 9) ? names[code - 1] : "OTHER";
}

static const char *cmd_word(uint8_t type)
{
    switch (type) {
    case TSP_HELLO_REQ:
    case TSP_HEARTBEAT: return "PING";
    case TSP_ARM: return "ARM";
    case TSP_DISARM: return "DISARM";
    case TSP_SET_THROTTLE: return "THR";
    case TSP_IMPULSE: return "IMP";
    case TSP_STOP: return "STOP";
    default: return "?";
    }
}

/* One CSV line (adds the newline). */
static uint8_t csv_line(char *s)
{
    size_t n = strlen(s);
    s[n++] = '\n';
    return tx_write((const uint8_t *)s, (uint16_t)n);
}

static char *fmt_f(char *p, float v, uint8_t prec)
{
    if (isnan(v)) {
        strcpy(p, "nan");
        return p + 3;
    }
    dtostrf(v, 1, prec, p);
    return p + strlen(p);
}

/* Sends one device message (TSP frame, or its CSV line); 0 when the TX ring had no room. */
static uint8_t emit(uint8_t type, const uint8_t *payload, uint8_t len)
{
    uint8_t ok;
    if (!csv_mode) {
        uint8_t frame[80];
        size_t n = tsp_encode(type, tx_seq, payload, len, frame);
        ok = tx_write(frame, (uint16_t)n);
    } else {
        char s[96];
        s[0] = 0;
        if (type == TSP_SAMPLE) {
            char *p = s;
            p += sprintf(p, "%lu,%u,", (unsigned long)tsp_get_u32(payload + 4),
                         tsp_get_u16(payload + 8));
            static const uint8_t prec[5] = {4, 5, 1, 3, 3};
            for (uint8_t i = 0; i < 5; i++) {
                float v;
                uint32_t u = tsp_get_u32(payload + 12 + 4 * i);
                memcpy(&v, &u, 4);
                p = fmt_f(p, v, prec[i]);
                if (i < 4)
                    *p++ = ',';
            }
            uint8_t x = 0;
            for (char *q = s; q < p; q++)
                x ^= (uint8_t)*q;
            sprintf(p, "*%02X", x);
        } else if (type == TSP_ACK) {
            const char *w = cmd_word(payload[2]);
            if (payload[3] == TSP_OK)
                sprintf(s, "#ACK %s OK %lu", w, (unsigned long)tsp_get_u32(payload + 5));
            else
                sprintf(s, "#ACK %s ERR %u", w, payload[3]);
        } else if (type == TSP_EVENT) {
            sprintf(s, "#EVENT %s %u %lu %lu", event_name(payload[0]), tsp_get_u16(payload + 2),
                    (unsigned long)tsp_get_u32(payload + 4),
                    (unsigned long)tsp_get_u32(payload + 8));
        } else if (type == TSP_HELLO) {
            sprintf(s, "# HELLO %s fw %u boot_id %08lx rate_hz %u", DEVICE_NAME,
                    tsp_get_u16(payload + 2), (unsigned long)boot_id, tsp_get_u16(payload + 12));
        } else if (type == TSP_LOG) {
            s[0] = '#';
            s[1] = ' ';
            uint8_t n = len - 1 < 80 ? len - 1 : 80;
            memcpy(s + 2, payload + 1, n);
            s[2 + n] = 0;
        }
        ok = csv_line(s);
    }
    if (ok)
        tx_seq++;
    return ok;
}

static void emit_event(uint8_t code, uint16_t arg, uint32_t t, uint32_t idx)
{
    uint8_t p[12];
    p[0] = code;
    p[1] = 0;
    tsp_put_u16(p + 2, arg);
    tsp_put_u32(p + 4, t);
    tsp_put_u32(p + 8, idx);
    emit(TSP_EVENT, p, 12);
}

static void emit_log(uint8_t severity, const char *text)
{
    uint8_t p[64];
    uint8_t n = (uint8_t)strlen(text);
    if (n > 62)
        n = 62;
    p[0] = severity;
    memcpy(p + 1, text, n);
    emit(TSP_LOG, p, (uint8_t)(n + 1));
}

static void emit_hello(uint32_t t)
{
    uint8_t p[34];
    memset(p, 0, sizeof p);
    p[0] = 0;                         /* proto_minor */
    p[1] = ESC_HZ >= 400 ? 1 : 0;     /* PWM400 or PWM50 */
    tsp_put_u16(p + 2, FW_VERSION);
    tsp_put_u32(p + 4, boot_id);
    tsp_put_u32(p + 8, t);
    tsp_put_u16(p + 12, rate_hz);
    tsp_put_u16(p + 14, (uint16_t)(0x1D | (have_torque ? 0x02 : 0))); /* thrust rpm V I [torque] */
    p[16] = MOTOR_POLES;
    p[17] = 0x0F; /* impulse, ramp, tare, set_rate */
    memcpy(p + 18, DEVICE_NAME, strlen(DEVICE_NAME));
    emit(TSP_HELLO, p, 34);
}

static void emit_ack(uint16_t seq, uint8_t type, uint8_t result, uint8_t dup, uint32_t t)
{
    uint8_t p[9];
    tsp_put_u16(p, seq);
    p[2] = type;
    p[3] = result;
    p[4] = dup ? 1 : 0;
    tsp_put_u32(p + 5, t);
    emit(TSP_ACK, p, 9);
}

/* ---- motor control ---- */
static uint16_t ramp_at(uint32_t t)
{
    uint32_t dt = t - ramp_start_us;
    if ((int32_t)dt < 0)
        dt = 0;
    if (dt >= ramp_dur_us)
        return ramp_to;
    int32_t a = ramp_from, b = ramp_to;
    return (uint16_t)(a + (int32_t)((float)(b - a) * (float)dt / (float)ramp_dur_us));
}

/* Motor stop and disarm: the ESC back to its minimum now. */
static void stop_motor(uint32_t t, uint32_t b_end, uint32_t idx_end)
{
    esc_write(0);
    if (pulse_state == PULSE_ACTIVE)
        emit_event(EV_IMPULSE_END, pulse_level, b_end, idx_end);
    pulse_state = PULSE_IDLE;
    ramp_on = 0;
    setpoint = 0;
    if (armed) {
        armed = 0;
        emit_event(EV_DISARMED, 0, t, index_now);
    }
}

/* The throttle and flags of the period starting at `b`. */
static uint16_t commit(uint32_t b, uint16_t *flags)
{
    uint16_t f = watchdog_tripped ? F_WATCHDOG_TRIPPED : 0;
    if (!armed) {
        *flags = f;
        return 0;
    }
    f |= F_ARMED;
    uint16_t base = setpoint;
    if (ramp_on) {
        base = ramp_at(b);
        if ((int32_t)(b - (ramp_start_us + ramp_dur_us)) >= 0)
            ramp_on = 0;
        else
            f |= F_RAMP_ACTIVE;
    }
    if (pulse_state == PULSE_PENDING) {
        emit_event(EV_IMPULSE_START, pulse_level, b, index_now);
        pulse_state = PULSE_ACTIVE;
    }
    if (pulse_state == PULSE_ACTIVE) {
        if (pulse_left > 0) {
            pulse_left--;
            *flags = f | F_IMPULSE_ACTIVE;
            return pulse_level;
        }
        emit_event(EV_IMPULSE_END, pulse_level, b, index_now);
        pulse_state = PULSE_IDLE;
    }
    *flags = f;
    return base;
}

static float read_rpm(uint32_t b, uint8_t *fresh)
{
    uint16_t edges;
    uint32_t last;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        edges = rpm_edges;
        last = rpm_last_us;
    }
    uint16_t n = edges - rpm_prev_edges;
    *fresh = 0;
    if (n > 0) {
        if (rpm_have_prev && last != rpm_prev_us) {
            rpm_value = 60.0e6f * (float)n / ((float)(last - rpm_prev_us) * RPM_PULSES_PER_REV);
            *fresh = 1;
        }
        rpm_prev_edges = edges;
        rpm_prev_us = last;
        rpm_have_prev = 1;
    } else if ((int32_t)(b - rpm_prev_us) > 250000L || !rpm_have_prev) {
        rpm_value = 0; /* under 120 rev/min with two pulses a turn: stopped */
        rpm_have_prev = 0;
    }
    return rpm_value;
}

/* Boundary `b`: commit the next period, read the sensors, send the last period's SAMPLE. */
static void boundary(uint32_t b)
{
    uint8_t first = !running;
    running = 1;
    uint16_t prev_u = cur_throttle, prev_f = cur_flags;
    if (!first)
        index_now++;
    /* signed: a command handled after `b` was due but before this boundary ran is newer */
    if (armed && (int32_t)(b - last_cmd_us) >= (int32_t)watchdog_us) {
        watchdog_tripped = 1;
        emit_event(EV_WATCHDOG_TRIP, 0, b, index_now);
        stop_motor(b, b, index_now);
    }
    cur_throttle = commit(b, &cur_flags);
    esc_write(cur_throttle);

    uint16_t flags = prev_f;
    float thrust = NAN, torque = NAN;
    /* both cells' readiness first: a conversion is read whole or not at all */
    uint8_t thrust_ready = hx_ready(HX_THRUST_DOUT), torque_ready = hx_ready(HX_TORQUE_DOUT);
    if (thrust_ready) {
        raw_thrust = hx_read(HX_THRUST_DOUT, HX_THRUST_SCK);
        have_thrust = 1;
        flags |= F_THRUST_FRESH;
    }
    if (torque_ready) {
        raw_torque = hx_read(HX_TORQUE_DOUT, HX_TORQUE_SCK);
        have_torque = 1;
    }
    if (have_thrust) {
        thrust = (float)(raw_thrust - cal.thrust_zero) / cal.thrust_counts_per_n;
        flags |= F_THRUST_VALID;
    }
    if (have_torque) {
        torque = (float)(raw_torque - cal.torque_zero) / cal.torque_counts_per_nm;
        flags |= F_TORQUE_VALID;
    }
    uint8_t fresh;
    float rpm = read_rpm(b, &fresh);
    flags |= F_RPM_VALID | (fresh ? F_RPM_FRESH : 0);
    float volts = (float)adc_read(ADC_VOLTAGE) * (ADC_REF_MV / 1024.0f) * VOLTAGE_DIVIDER / 1000.0f;
    float mv = (float)adc_read(ADC_CURRENT) * (ADC_REF_MV / 1024.0f);
    float amps = (mv - CURRENT_OFFSET_MV) / CURRENT_MV_PER_A;
    flags |= F_VOLTAGE_VALID | F_CURRENT_VALID;

    if (!first) {
        uint8_t p[32];
        tsp_put_u32(p, index_now - 1);
        tsp_put_u32(p + 4, b);
        tsp_put_u16(p + 8, prev_u);
        tsp_put_u16(p + 10, flags);
        tsp_put_f32(p + 12, thrust);
        tsp_put_f32(p + 16, torque);
        tsp_put_f32(p + 20, rpm);
        tsp_put_f32(p + 24, volts);
        tsp_put_f32(p + 28, amps);
        if (!emit(TSP_SAMPLE, p, 32)) {
            tx_dropped++;
        } else if (tx_dropped) {
            emit_event(EV_TX_OVERRUN, tx_dropped, b, index_now - 1);
            tx_dropped = 0;
        }
    }
    if ((int32_t)(b - next_hello_us) >= 0) {
        emit_hello(b);
        while ((int32_t)(b - next_hello_us) >= 0)
            next_hello_us += 1000000UL;
    }
    /* b_k = base + k·10⁶/rate, re-based every second so k·10⁶ stays in 32 bits */
    if (++sched_k >= rate_hz) {
        sched_base_us += 1000000UL;
        sched_k = 0;
    }
    next_boundary_us = sched_base_us + (uint32_t)sched_k * 1000000UL / rate_hz;
}

/* ---- commands ---- */
static uint8_t execute(uint8_t type, const uint8_t *p, uint32_t now, uint32_t *t_eff)
{
    *t_eff = now;
    switch (type) {
    case TSP_HELLO_REQ:
        emit_hello(now);
        return TSP_OK;
    case TSP_ARM: {
        uint16_t wd = tsp_get_u16(p);
        if (tsp_get_u32(p + 2) != ARM_KEY)
            return TSP_BAD_KEY;
        if (armed && (setpoint != 0 || ramp_on || pulse_state != PULSE_IDLE))
            return TSP_BAD_STATE;
        if (wd < 100 || wd > 5000)
            return TSP_OUT_OF_RANGE;
        watchdog_us = (uint32_t)wd * 1000UL;
        watchdog_tripped = 0;
        if (!armed) {
            armed = 1;
            emit_event(EV_ARMED, wd, now, index_now);
        }
        return TSP_OK;
    }
    case TSP_DISARM:
    case TSP_STOP:
        stop_motor(now, next_boundary_us, index_now + 1);
        return TSP_OK;
    case TSP_SET_THROTTLE: {
        uint16_t level = tsp_get_u16(p), ramp_ms = tsp_get_u16(p + 2);
        if (!armed)
            return TSP_BAD_STATE;
        if (level > THROTTLE_FULL)
            return TSP_OUT_OF_RANGE;
        if (pulse_state != PULSE_IDLE)
            return TSP_BUSY;
        uint32_t start = next_boundary_us;
        uint16_t from = ramp_on ? ramp_at(start) : setpoint;
        setpoint = level;
        ramp_on = ramp_ms > 0 && from != level;
        ramp_from = from;
        ramp_to = level;
        ramp_start_us = start;
        ramp_dur_us = (uint32_t)ramp_ms * 1000UL;
        *t_eff = next_boundary_us;
        return TSP_OK;
    }
    case TSP_IMPULSE: {
        uint16_t level = tsp_get_u16(p);
        uint32_t width = tsp_get_u32(p + 2);
        if (!armed)
            return TSP_BAD_STATE;
        if (level > THROTTLE_FULL || width == 0 || width > MAX_IMPULSE_US)
            return TSP_OUT_OF_RANGE;
        if (pulse_state != PULSE_IDLE || ramp_on)
            return TSP_BUSY;
        uint32_t periods = (uint32_t)(((uint64_t)width * rate_hz + 999999UL) / 1000000UL);
        pulse_state = PULSE_PENDING;
        pulse_level = level;
        pulse_left = periods ? periods : 1;
        *t_eff = next_boundary_us;
        return TSP_OK;
    }
    case TSP_HEARTBEAT:
        return TSP_OK;
    case TSP_SET_RATE: {
        uint16_t hz = tsp_get_u16(p);
        if (armed)
            return TSP_BAD_STATE;
        if (hz < MIN_RATE_HZ || hz > MAX_RATE_HZ)
            return TSP_OUT_OF_RANGE;
        sched_base_us = next_boundary_us;
        sched_k = 0;
        rate_hz = hz;
        emit_hello(now);
        return TSP_OK;
    }
    case TSP_TARE:
        if (armed)
            return TSP_BAD_STATE;
        cal.thrust_zero = raw_thrust;
        cal.torque_zero = raw_torque;
        calib_save();
        emit_event(EV_TARE_DONE, 0, now, index_now);
        return TSP_OK;
    default:
        return TSP_UNKNOWN_TYPE;
    }
}

/* A well-formed command: duplicates answered from memory, the rest executed and answered. */
static void command(uint16_t seq, uint8_t type, const uint8_t *p)
{
    uint32_t now = micros();
    last_cmd_us = now;
    struct dedup *hit = 0;
    for (uint8_t i = 0; i < 8; i++) {
        struct dedup *d = &dedup[i];
        if (d->used && d->seq == seq && d->type == type && (int32_t)(now - d->at_us) < 1000000L &&
            (!hit || (int32_t)(d->at_us - hit->at_us) > 0))
            hit = d;
    }
    if (hit) {
        emit_ack(seq, type, hit->result, 1, now);
        return;
    }
    uint32_t t_eff;
    uint8_t r = execute(type, p, now, &t_eff);
    struct dedup *d = &dedup[dedup_next];
    dedup_next = (dedup_next + 1) & 7;
    d->seq = seq;
    d->type = type;
    d->result = r;
    d->used = 1;
    d->at_us = now;
    emit_ack(seq, type, r, 0, t_eff);
}

static uint8_t min_payload(uint8_t type)
{
    switch (type) {
    case TSP_ARM:
    case TSP_IMPULSE: return 6;
    case TSP_SET_THROTTLE: return 4;
    case TSP_SET_RATE: return 2;
    default: return 0;
    }
}

/* A storm of bad frames or UART framing errors while armed stops the motor. */
static void count_bad(uint8_t n)
{
    uint32_t now = micros();
    if ((int32_t)(now - storm_start_us) > (int32_t)(STORM_WINDOW_MS * 1000L)) {
        storm_start_us = now;
        storm_count = 0;
    }
    storm_count = (uint8_t)(storm_count + n > 250 ? 250 : storm_count + n);
    if (storm_count >= STORM_COUNT && armed) {
        stop_motor(now, next_boundary_us, index_now + 1);
        emit_log(3, "framing error storm: motor stopped");
        storm_count = 0;
    }
}

static void tsp_frame(uint8_t *buf, uint8_t n)
{
    uint8_t type;
    uint16_t seq;
    const uint8_t *p;
    size_t len;
    int r = tsp_decode(buf, n, &type, &seq, &p, &len);
    if (r == -4) {
        csv_mode = 0;
        emit_ack(seq, type, TSP_VERSION_ERR, 0, micros());
        return;
    }
    if (r < 0) {
        count_bad(1);
        return;
    }
    csv_mode = 0;
    if (type < 0x01 || type > 0x09) {
        emit_ack(seq, type, TSP_UNKNOWN_TYPE, 0, micros());
        return;
    }
    if (len < min_payload(type)) {
        emit_ack(seq, type, TSP_BAD_LENGTH, 0, micros());
        return;
    }
    command(seq, type, p);
}

/* ---- CSV fallback: one command line (PROTOCOL.md §6), plus TARE and CAL for calibration ---- */
static uint16_t csv_seq;

static void csv_command(char *line)
{
    char *save;
    char *w = strtok_r(line, " \t\r", &save);
    if (!w)
        return;
    char *a1 = strtok_r(0, " \t\r", &save);
    char *a2 = strtok_r(0, " \t\r", &save);
    uint8_t p[6];
    uint8_t type;
    memset(p, 0, sizeof p);
    if (!strcmp(w, "PING")) {
        type = TSP_HELLO_REQ;
    } else if (!strcmp(w, "ARM") && a1) {
        type = TSP_ARM;
        tsp_put_u16(p, (uint16_t)atol(a1));
        tsp_put_u32(p + 2, ARM_KEY);
    } else if (!strcmp(w, "DISARM")) {
        type = TSP_DISARM;
    } else if (!strcmp(w, "STOP")) {
        type = TSP_STOP;
    } else if (!strcmp(w, "THR") && a1) {
        type = TSP_SET_THROTTLE;
        tsp_put_u16(p, (uint16_t)atol(a1));
        tsp_put_u16(p + 2, a2 ? (uint16_t)atol(a2) : 0);
    } else if (!strcmp(w, "IMP") && a1 && a2) {
        type = TSP_IMPULSE;
        tsp_put_u16(p, (uint16_t)atol(a1));
        tsp_put_u32(p + 2, (uint32_t)atol(a2));
    } else if (!strcmp(w, "TARE")) {
        type = TSP_TARE;
    } else if (!strcmp(w, "CAL") && a1 && !armed && have_thrust) {
        /* CAL <grams>: the known mass on the thrust cell sets the counts per newton */
        float n = (float)atof(a1) * 0.00980665f;
        if (n > 0) {
            cal.thrust_counts_per_n = (float)(raw_thrust - cal.thrust_zero) / n;
            calib_save();
        }
        char s[48];
        sprintf(s, "# CAL thrust %ld counts/N", (long)cal.thrust_counts_per_n);
        csv_mode = 1;
        csv_line(s);
        return;
    } else {
        if (csv_mode) {
            char s[24];
            sprintf(s, "#ACK ? ERR %u", TSP_UNKNOWN_TYPE);
            csv_line(s);
        }
        return;
    }
    csv_mode = 1;
    command(csv_seq++, type, p);
}

/* ---- receive: COBS frames up to 0x00, text lines up to '\n', both at once ---- */
static uint8_t frame_buf[64], frame_len, frame_over;
static char line_buf[64];
static uint8_t line_len, line_over;

static void rx_byte(uint8_t b)
{
    if (b == '!' && frame_len == 0 && line_len == 0) {
        /* `!` starts no valid command frame (a block of 33 bytes): stop, in either mode */
        uint32_t now = micros();
        stop_motor(now, next_boundary_us, index_now + 1);
        last_cmd_us = now;
        if (csv_mode)
            emit_ack(csv_seq++, TSP_STOP, TSP_OK, 0, now);
        return;
    }
    if (b == 0) {
        if (frame_len && !frame_over)
            tsp_frame(frame_buf, frame_len);
        else if (frame_over)
            count_bad(1);
        frame_len = frame_over = 0;
        line_len = line_over = 0;
        return;
    }
    if (frame_len < sizeof frame_buf)
        frame_buf[frame_len++] = b;
    else
        frame_over = 1;
    if (b == '\n') {
        if (line_len && !line_over) {
            line_buf[line_len] = 0;
            csv_command(line_buf);
        }
        line_len = line_over = 0;
        if (csv_mode)
            frame_len = frame_over = 0;
        return;
    }
    if (line_len < sizeof line_buf - 1)
        line_buf[line_len++] = (char)b;
    else
        line_over = 1;
}

static void poll_rx(void)
{
    uint8_t errs;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        errs = rx_errors;
        rx_errors = 0;
    }
    if (errs)
        count_bad(errs);
    while (rx_tail != rx_head) {
        uint8_t b = rx_buf[rx_tail];
        rx_tail = (uint8_t)((rx_tail + 1) % RX_SIZE);
        rx_byte(b);
    }
}

/* ---- boot ---- */
static uint32_t mix(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352dUL;
    x ^= x >> 15;
    x *= 0x846ca68bUL;
    x ^= x >> 16;
    return x;
}

int main(void)
{
    esc_init();
    HX_DDR |= _BV(HX_THRUST_SCK) | _BV(HX_TORQUE_SCK);
    HX_PORT &= ~(_BV(HX_THRUST_SCK) | _BV(HX_TORQUE_SCK));
    HX_PORT |= _BV(HX_THRUST_DOUT) | _BV(HX_TORQUE_DOUT); /* pull-ups */
    PORTD |= _BV(RPM_PIN);                                 /* pull-up */
    DIDR0 = _BV(ADC_VOLTAGE) | _BV(ADC_CURRENT);           /* analog only */
    TCCR0A = _BV(WGM01);
    OCR0A = 249;
    TCCR0B = _BV(CS01) | _BV(CS00); /* 16 MHz / 64 / 250 = 1 kHz */
    TIMSK0 = _BV(OCIE0A);
    EICRA = _BV(ISC01) | _BV(ISC00);
    EIMSK = _BV(INT0);
    uart_init();
    calib_load();
    cal.boots++;
    calib_save();
    boot_id = mix(((uint32_t)cal.boots << 16) ^ adc_read(6) ^ ((uint32_t)mcusr_mirror << 8));
#ifdef CSV_DEFAULT
    csv_mode = 1;
#endif
    wdt_enable(WDTO_250MS);
    sei();

    emit_hello(0);
    emit_event(EV_RESET_CAUSE, mcusr_mirror, 0, 0);
    emit_log(2, DEVICE_NAME " booted");
    next_hello_us = 1000000UL;
    sched_base_us = micros();
    next_boundary_us = sched_base_us;

    set_sleep_mode(SLEEP_MODE_IDLE);
    for (;;) {
        wdt_reset();
        poll_rx();
        uint32_t now = micros();
        if ((int32_t)(now - next_boundary_us) >= 0)
            boundary(next_boundary_us);
#ifndef NO_SLEEP
        else if (rx_tail == rx_head) {
            cli();
            if (rx_tail == rx_head) {
                sleep_enable();
                sei();
                sleep_cpu();
                sleep_disable();
            }
            sei();
        }
#endif
    }
}
