/* The reference firmware's ELF on an emulated ATmega328P (simavr), its UART on a pseudo-terminal,
 * the loop closed through a plant process (`propid sim --plant-pipe`).
 *
 * Every PLANT_STEP_US of emulated time the harness sends the plant the throttle the ESC pin
 * commands (the last OC1A pulse width measured from its edges, mapped from ESC_MIN_US..
 * ESC_MAX_US to 0..1) and reads back `thrust torque rpm voltage current`; it then presents them
 * as the stand's sensors do: the HX711s' conversions (DOUT low when ready, 24 bits clocked out
 * on the firmware's SCK edges), rpm pulses on INT0, millivolts on the ADC pins. Emulated time
 * is held to the wall clock (the host's heartbeats and the firmware's watchdog are real time).
 *
 * stdout: the pty path first, then one JSON line per ESC pulse-width change of 20 us or more
 * ({"t_s":…, "esc_us":…}) and a last {"type":"harness_stats",…} line when the run ends.
 * Usage: harness ELF --plant "CMD" [--link PATH] [--seconds S] [--hx711-hz HZ] */
#define _GNU_SOURCE
#include "config.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <avr_adc.h>
#include <avr_ioport.h>
#include <parts/uart_pty.h>
#include <sim_avr.h>
#include <sim_elf.h>
#include <sim_time.h>

#define PLANT_STEP_US 1000

static avr_t *avr;
static uart_pty_t pty;
static FILE *plant_in, *plant_out; /* to and from the plant process */
static volatile sig_atomic_t stop_requested;

/* ESC pin */
static double esc_us = 0;          /* last complete pulse, us (0: none yet) */
static double esc_reported = -1e9; /* last width printed */
static avr_cycle_count_t esc_last_edge;
static unsigned long esc_pulses;

/* plant outputs */
static double m_thrust, m_torque, m_rpm, m_volts, m_amps;
static unsigned long plant_steps;

/* HX711 model */
struct hx711 {
    int dout, sck;        /* HX_PORT_NAME bits */
    avr_irq_t *dout_irq;
    int32_t value;        /* the conversion being clocked out */
    int32_t pending;      /* the newest conversion */
    int has_pending;
    int pulses;           /* SCK pulses since DOUT went low */
    int reading;
    unsigned long conversions, reads;
};
static struct hx711 hx_thrust = {HX_THRUST_DOUT, HX_THRUST_SCK, 0, 0, 0, 0, 0, 0, 0, 0};
static struct hx711 hx_torque = {HX_TORQUE_DOUT, HX_TORQUE_SCK, 0, 0, 0, 0, 0, 0, 0, 0};
static double hx_period_us = 1000; /* conversion period; --hx711-hz */

static avr_irq_t *rpm_irq;
static unsigned long rpm_pulses;

static double emu_s(void) { return (double)avr->cycle / (double)avr->frequency; }

/* Timer1's registers in data space (ATmega328P datasheet §30, register summary). */
#define REG_TCCR1B 0x81
#define REG_OCR1AL 0x88
#define REG_OCR1AH 0x89

/* The ESC pin's rising edge (simavr sets OC1A at BOTTOM). simavr 1.6 keeps the compare edge
 * where it was when the timer was configured, so the falling edge is the compare unit's, modelled
 * here: OCR1A is latched at BOTTOM (double-buffered) and the pin falls (OCR1A + 1) timer ticks
 * later. */
static void on_esc(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    static const uint16_t prescale[8] = {0, 1, 8, 64, 256, 1024, 0, 0};
    if (!value)
        return;
    uint16_t div = prescale[avr->data[REG_TCCR1B] & 7];
    if (!div)
        return;
    uint32_t ocr = avr->data[REG_OCR1AL] | ((uint32_t)avr->data[REG_OCR1AH] << 8);
    esc_last_edge = avr->cycle;
    esc_us = (double)(ocr + 1) * div * 1e6 / (double)avr->frequency;
    esc_pulses++;
    if (fabs(esc_us - esc_reported) >= 20.0) {
        esc_reported = esc_us;
        printf("{\"t_s\":%.4f,\"esc_us\":%.1f}\n", emu_s(), esc_us);
        fflush(stdout);
    }
}

/* The ESC's throttle, 0..1: no pulse for 100 ms (pin low or stuck) is no throttle. */
static double esc_throttle(void)
{
    double since = (double)(avr->cycle - esc_last_edge) / (double)avr->frequency;
    if (esc_us <= 0 || since > 0.1)
        return 0;
    double u = (esc_us - ESC_MIN_US) / (double)(ESC_MAX_US - ESC_MIN_US);
    return u < 0 ? 0 : u > 1 ? 1 : u;
}

static void hx_set_dout(struct hx711 *h, int level) { avr_raise_irq(h->dout_irq, level); }

static void hx_convert(struct hx711 *h, double value, double counts_per_unit)
{
    double c = round(value * counts_per_unit);
    if (c > 8388607)
        c = 8388607;
    if (c < -8388608)
        c = -8388608;
    h->pending = (int32_t)c;
    h->has_pending = 1;
    h->conversions++;
    if (!h->reading) {
        h->value = h->pending;
        h->has_pending = 0;
        hx_set_dout(h, 0);
    }
}

/* SCK edge from the firmware: on each rising edge the next bit (MSB first) goes on DOUT; the
 * 25th edge ends the read (DOUT high until the next conversion). */
static void on_sck(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    struct hx711 *h = param;
    if (!value)
        return;
    if (h->pulses < 24) {
        h->reading = 1;
        int bit = ((uint32_t)h->value >> (23 - h->pulses)) & 1;
        h->pulses++;
        hx_set_dout(h, bit);
        return;
    }
    h->pulses = 0;
    h->reading = 0;
    h->reads++;
    if (h->has_pending) {
        h->value = h->pending;
        h->has_pending = 0;
        hx_set_dout(h, 0);
    } else {
        hx_set_dout(h, 1);
    }
}

/* The rpm sensor: a square wave, RPM_PULSES_PER_REV rising edges a turn. */
static avr_cycle_count_t rpm_tick(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)param;
    static int level;
    double hz = m_rpm * RPM_PULSES_PER_REV / 60.0;
    if (hz < 2) /* stopped: look again in 10 ms */
        return when + (avr_cycle_count_t)(a->frequency / 100);
    level = !level;
    avr_raise_irq(rpm_irq, level);
    rpm_pulses += level;
    return when + (avr_cycle_count_t)((double)a->frequency / hz / 2);
}

static double next_conversion_us;

static avr_cycle_count_t plant_tick(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)param;
    fprintf(plant_in, "%.6f\n", esc_throttle());
    fflush(plant_in);
    char line[256];
    if (!fgets(line, sizeof line, plant_out) ||
        sscanf(line, "%lf %lf %lf %lf %lf", &m_thrust, &m_torque, &m_rpm, &m_volts, &m_amps) != 5) {
        fprintf(stderr, "harness: the plant process ended or wrote %s", line);
        stop_requested = 1;
        return 0;
    }
    plant_steps++;
    double t_us = emu_s() * 1e6;
    if (t_us >= next_conversion_us) {
        hx_convert(&hx_thrust, m_thrust, THRUST_COUNTS_PER_N);
        hx_convert(&hx_torque, m_torque, TORQUE_COUNTS_PER_NM);
        while (next_conversion_us <= t_us)
            next_conversion_us += hx_period_us;
    }
    avr_irq_t *adc = avr_io_getirq(a, AVR_IOCTL_ADC_GETIRQ, 0);
    avr_raise_irq(adc + ADC_VOLTAGE, (uint32_t)(m_volts / VOLTAGE_DIVIDER * 1000.0));
    double mv = CURRENT_OFFSET_MV + CURRENT_MV_PER_A * m_amps;
    avr_raise_irq(adc + ADC_CURRENT, (uint32_t)(mv < 0 ? 0 : mv));
    return when + avr_usec_to_cycles(a, PLANT_STEP_US);
}

/* Sleeping is paced by the main loop against the wall clock, not here. */
static void no_sleep(avr_t *a, avr_cycle_count_t how_long)
{
    (void)a;
    (void)how_long;
}

static double wall_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

static void start_plant(const char *cmd)
{
    int to[2], from[2];
    if (pipe(to) || pipe(from)) {
        perror("harness: pipe");
        exit(2);
    }
    pid_t pid = fork();
    if (pid < 0) {
        perror("harness: fork");
        exit(2);
    }
    if (pid == 0) {
        dup2(to[0], 0);
        dup2(from[1], 1);
        close(to[1]);
        close(from[0]);
        execl("/bin/sh", "sh", "-c", cmd, (char *)0);
        _exit(127);
    }
    close(to[0]);
    close(from[1]);
    plant_in = fdopen(to[1], "w");
    plant_out = fdopen(from[0], "r");
}

int main(int argc, char **argv)
{
    const char *elf = 0, *plant = 0, *link = 0;
    double seconds = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--plant") && i + 1 < argc)
            plant = argv[++i];
        else if (!strcmp(argv[i], "--link") && i + 1 < argc)
            link = argv[++i];
        else if (!strcmp(argv[i], "--seconds") && i + 1 < argc)
            seconds = atof(argv[++i]);
        else if (!strcmp(argv[i], "--hx711-hz") && i + 1 < argc)
            hx_period_us = 1e6 / atof(argv[++i]);
        else if (argv[i][0] != '-' && !elf)
            elf = argv[i];
        else {
            fprintf(stderr, "usage: harness ELF --plant CMD [--link PATH] [--seconds S] "
                            "[--hx711-hz HZ]\n");
            return 2;
        }
    }
    if (!elf || !plant) {
        fprintf(stderr, "usage: harness ELF --plant CMD [--link PATH] [--seconds S]\n");
        return 2;
    }
    elf_firmware_t fw;
    memset(&fw, 0, sizeof fw);
    if (elf_read_firmware(elf, &fw)) {
        fprintf(stderr, "harness: cannot read %s\n", elf);
        return 2;
    }
    avr = avr_make_mcu_by_name("atmega328p");
    if (!avr) {
        fprintf(stderr, "harness: simavr has no atmega328p\n");
        return 2;
    }
    avr_init(avr);
    fw.frequency = F_CPU;
    avr_load_firmware(avr, &fw);
    avr->frequency = F_CPU;
    avr->vcc = avr->avcc = avr->aref = 5000;
    avr->sleep = no_sleep;
    avr->log = 1;

    signal(SIGPIPE, SIG_IGN);
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    start_plant(plant);

    uart_pty_init(avr, &pty);
    uart_pty_connect(&pty, '0');
    const char *path = pty.port[0].slavename;
    if (link) {
        unlink(link);
        if (symlink(path, link)) {
            perror("harness: symlink");
            return 2;
        }
        path = link;
    }
    printf("%s\n", path);
    fflush(stdout);

    /* the ESC pin: OC1A = PB1, its edges as the port sees them */
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('B'), 1), on_esc, 0);
    struct hx711 *hx[2] = {&hx_thrust, &hx_torque};
    for (int i = 0; i < 2; i++) {
        hx[i]->dout_irq = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(HX_PORT_NAME), hx[i]->dout);
        avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(HX_PORT_NAME), hx[i]->sck),
                                on_sck, hx[i]);
        hx_set_dout(hx[i], 1);
    }
    rpm_irq = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), RPM_PIN);
    avr_raise_irq(rpm_irq, 0);
    avr_cycle_timer_register_usec(avr, PLANT_STEP_US, plant_tick, 0);
    avr_cycle_timer_register_usec(avr, 1000, rpm_tick, 0);

    double t0 = wall_s(), max_lag = 0;
    int state = cpu_Running;
    unsigned long n = 0;
    while (!stop_requested) {
        state = avr_run(avr);
        if (state == cpu_Done || state == cpu_Crashed)
            break;
        if ((++n & 1023) && state != cpu_Sleeping)
            continue;
        double emu = emu_s(), wall = wall_s() - t0;
        if (emu > wall + 0.0005) {
            struct timespec ts = {0, (long)((emu - wall) * 1e9)};
            nanosleep(&ts, 0);
        } else if (wall - emu > max_lag) {
            max_lag = wall - emu;
        }
        if (seconds > 0 && emu >= seconds)
            break;
    }
    printf("{\"type\":\"harness_stats\",\"emulated_s\":%.3f,\"wall_s\":%.3f,\"max_lag_s\":%.4f,"
           "\"state\":%d,\"plant_steps\":%lu,\"esc_pulses\":%lu,\"esc_us\":%.1f,"
           "\"hx711_reads\":%lu,\"rpm_pulses\":%lu}\n",
           emu_s(), wall_s() - t0, max_lag, state, plant_steps, esc_pulses, esc_us, hx_thrust.reads,
           rpm_pulses);
    fflush(stdout);
    /* no uart_pty_stop(): its thread does not end on the SIGINT it is sent; exit ends it */
    if (link)
        unlink(link);
    fclose(plant_in);
    return state == cpu_Crashed ? 1 : 0;
}
