/* Build-time settings of the reference firmware: pins, ESC signal, default calibration. Each can
 * be overridden on the make command line (make CFLAGS_EXTRA=-DESC_HZ=50). The harness
 * (harness/harness.c) includes this file too, so the emulated stand is wired as the real one. */
#ifndef PROPID_FW_CONFIG_H
#define PROPID_FW_CONFIG_H

#ifndef F_CPU
#define F_CPU 16000000UL
#endif
#ifndef BAUD
#define BAUD 250000UL /* exact from 16 MHz (UBRR 3, no U2X) */
#endif

/* ESC: servo PWM on OC1A = PB1 (Arduino D9), Timer1 at 0.5 us per tick. */
#ifndef ESC_HZ
#define ESC_HZ 400 /* 50..490 */
#endif
#ifndef ESC_MIN_US
#define ESC_MIN_US 1000
#endif
#ifndef ESC_MAX_US
#define ESC_MAX_US 2000
#endif

/* HX711 load cells on port C: thrust DOUT PC2 (A2) SCK PC3 (A3); torque DOUT PC4 (A4) SCK PC5
 * (A5). Port D (UART, rpm) is then never written after setup. */
#define HX_PORT PORTC
#define HX_PIN PINC
#define HX_DDR DDRC
#define HX_PORT_NAME 'C'
#define HX_THRUST_DOUT 2
#define HX_THRUST_SCK 3
#define HX_TORQUE_DOUT 4
#define HX_TORQUE_SCK 5
/* rpm sensor on INT0 = PD2 (D2), rising edges. */
#define RPM_PIN 2
/* ADC channels: battery voltage divider on A0, current sensor on A1. */
#define ADC_VOLTAGE 0
#define ADC_CURRENT 1

/* Default calibration (EEPROM overrides it once CAL or TARE has stored one). */
#ifndef THRUST_COUNTS_PER_N
#define THRUST_COUNTS_PER_N 73500.0 /* 5 kg, 2 mV/V cell, gain 128 */
#endif
#ifndef TORQUE_COUNTS_PER_NM
#define TORQUE_COUNTS_PER_NM 1500000.0
#endif
#ifndef RPM_PULSES_PER_REV
#define RPM_PULSES_PER_REV 2 /* optical sensor, two-blade propeller */
#endif
#ifndef VOLTAGE_DIVIDER
#define VOLTAGE_DIVIDER 11.0 /* 10k over 1k: 0..55 V */
#endif
#ifndef CURRENT_OFFSET_MV
#define CURRENT_OFFSET_MV 600.0 /* ACS758-050U: 0.6 V at 0 A */
#endif
#ifndef CURRENT_MV_PER_A
#define CURRENT_MV_PER_A 60.0
#endif
#define ADC_REF_MV 5000.0

/* Protocol defaults. */
#define DEFAULT_RATE_HZ 200
#define MIN_RATE_HZ 10
#define MAX_RATE_HZ 400
#define FW_VERSION 1
#define MOTOR_POLES 14
#define DEVICE_NAME "propid-fw"
/* A storm: this many framing errors or bad frames within STORM_WINDOW_MS while armed. */
#define STORM_COUNT 16
#define STORM_WINDOW_MS 250

#endif
