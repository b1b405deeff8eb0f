//! TSP/1 messages, both directions (PROTOCOL.md §3, §4), as typed payload structs.
//!
//! Everything here is `Copy` and fixed-size (a LOG text lives in a 200-byte array), so decoding
//! a frame never allocates. Wire layouts (offsets, little-endian) live in
//! [`payload`](super::payload); this module holds the types, codes and helpers.

/// Message type codes (`type` byte of the frame body).
pub mod msg_type {
    /// Host → device: ask for a HELLO.
    pub const HELLO_REQ: u8 = 0x01;
    /// Host → device: arm with a watchdog.
    pub const ARM: u8 = 0x02;
    /// Host → device: disarm.
    pub const DISARM: u8 = 0x03;
    /// Host → device: set the throttle (step or ramp).
    pub const SET_THROTTLE: u8 = 0x04;
    /// Host → device: device-timed pulse.
    pub const IMPULSE: u8 = 0x05;
    /// Host → device: stop everything.
    pub const STOP: u8 = 0x06;
    /// Host → device: reset the watchdog.
    pub const HEARTBEAT: u8 = 0x07;
    /// Host → device: change the sample rate.
    pub const SET_RATE: u8 = 0x08;
    /// Host → device: tare the load cell.
    pub const TARE: u8 = 0x09;
    /// Device → host: identity and state.
    pub const HELLO: u8 = 0x41;
    /// Device → host: one measurement.
    pub const SAMPLE: u8 = 0x42;
    /// Device → host: answer to a command.
    pub const ACK: u8 = 0x43;
    /// Device → host: something happened.
    pub const EVENT: u8 = 0x44;
    /// Device → host: debug text.
    pub const LOG: u8 = 0x45;
}

/// ESC protocol reported in HELLO.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum EscProtocol {
    /// 50 Hz PWM.
    Pwm50,
    /// 400 Hz PWM.
    Pwm400,
    /// OneShot125.
    OneShot125,
    /// DShot150.
    DShot150,
    /// DShot300.
    DShot300,
    /// DShot600.
    DShot600,
    /// DShot1200.
    DShot1200,
    /// No ESC (255).
    None,
    /// A code this version does not know.
    Other(u8),
}

impl EscProtocol {
    /// From the wire code.
    pub fn from_u8(v: u8) -> Self {
        match v {
            0 => Self::Pwm50,
            1 => Self::Pwm400,
            2 => Self::OneShot125,
            3 => Self::DShot150,
            4 => Self::DShot300,
            5 => Self::DShot600,
            6 => Self::DShot1200,
            255 => Self::None,
            o => Self::Other(o),
        }
    }

    /// The wire code.
    pub fn to_u8(self) -> u8 {
        match self {
            Self::Pwm50 => 0,
            Self::Pwm400 => 1,
            Self::OneShot125 => 2,
            Self::DShot150 => 3,
            Self::DShot300 => 4,
            Self::DShot600 => 5,
            Self::DShot1200 => 6,
            Self::None => 255,
            Self::Other(o) => o,
        }
    }
}

/// HELLO capability bits (`caps`).
pub mod caps {
    /// Device-timed impulses.
    pub const IMPULSE: u8 = 1 << 0;
    /// Throttle ramps.
    pub const RAMP: u8 = 1 << 1;
    /// Load-cell tare.
    pub const TARE: u8 = 1 << 2;
    /// SET_RATE.
    pub const SET_RATE: u8 = 1 << 3;
}

/// 0x41 HELLO: at boot, on HELLO_REQ and every second.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Hello {
    /// Protocol minor version.
    pub proto_minor: u8,
    /// ESC protocol in use.
    pub esc_protocol: EscProtocol,
    /// Firmware version.
    pub fw_version: u16,
    /// Random per boot: a change means the device reset.
    pub boot_id: u32,
    /// Device clock now, µs.
    pub t_us: u32,
    /// Nominal sample rate, Hz.
    pub sample_rate_hz: u16,
    /// Channels present: bit `i` = SAMPLE flag bit `i + 1` (bit0 thrust … bit4 current).
    pub channels: u16,
    /// Motor pole count (0 unknown).
    pub motor_poles: u8,
    /// Capabilities, see [`caps`].
    pub caps: u8,
    /// Device name, NUL-padded ASCII.
    pub name: [u8; 16],
}

impl Hello {
    /// The name up to the first NUL (invalid UTF-8 is cut at the first bad byte).
    pub fn name_str(&self) -> &str {
        let end = self.name.iter().position(|&b| b == 0).unwrap_or(16);
        utf8_prefix(&self.name[..end])
    }

    /// A NUL-padded name field from `name` (truncated to 16 bytes at a char boundary).
    pub fn name_field(name: &str) -> [u8; 16] {
        let mut out = [0u8; 16];
        let cut = floor_char_boundary(name, 16);
        out[..cut].copy_from_slice(&name.as_bytes()[..cut]);
        out
    }

    /// True when the SAMPLE channel with this `*_VALID` flag is present.
    pub fn has_channel(&self, valid_flag: SampleFlags) -> bool {
        (self.channels << 1) & valid_flag.0 != 0
    }

    /// True when all bits of `cap` (see [`caps`]) are set.
    pub fn has_cap(&self, cap: u8) -> bool {
        self.caps & cap == cap
    }
}

/// SAMPLE flags (PROTOCOL.md §3), a `u16` bit set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, serde::Serialize)]
pub struct SampleFlags(pub u16);

impl SampleFlags {
    /// bit0: motor armed.
    pub const ARMED: Self = Self(1 << 0);
    /// bit1: thrust is measured.
    pub const THRUST_VALID: Self = Self(1 << 1);
    /// bit2: torque is measured.
    pub const TORQUE_VALID: Self = Self(1 << 2);
    /// bit3: rotor speed is measured.
    pub const RPM_VALID: Self = Self(1 << 3);
    /// bit4: supply voltage is measured.
    pub const VOLTAGE_VALID: Self = Self(1 << 4);
    /// bit5: current is measured.
    pub const CURRENT_VALID: Self = Self(1 << 5);
    /// bit6: a device-timed impulse is running.
    pub const IMPULSE_ACTIVE: Self = Self(1 << 6);
    /// bit7: a throttle ramp is running.
    pub const RAMP_ACTIVE: Self = Self(1 << 7);
    /// bit8: the watchdog tripped.
    pub const WATCHDOG_TRIPPED: Self = Self(1 << 8);
    /// bit9: a limit cut the motor off.
    pub const LIMIT_CUTOFF: Self = Self(1 << 9);
    /// bit10: a new thrust conversion since the last SAMPLE.
    pub const THRUST_FRESH: Self = Self(1 << 10);
    /// bit11: a new rpm measurement since the last SAMPLE.
    pub const RPM_FRESH: Self = Self(1 << 11);
    /// bit12: ESC telemetry is stale.
    pub const ESC_TELEM_STALE: Self = Self(1 << 12);
    /// bit13: the ADC saturated.
    pub const ADC_SATURATED: Self = Self(1 << 13);

    /// The raw bits.
    pub fn bits(self) -> u16 {
        self.0
    }

    /// True when every bit of `other` is set.
    pub fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }

    /// Set the bits of `other`.
    pub fn insert(&mut self, other: Self) {
        self.0 |= other.0;
    }

    /// Clear the bits of `other`.
    pub fn remove(&mut self, other: Self) {
        self.0 &= !other.0;
    }
}

impl std::ops::BitOr for SampleFlags {
    type Output = Self;
    fn bitor(self, rhs: Self) -> Self {
        Self(self.0 | rhs.0)
    }
}

/// Throttle full scale on the wire: 10000 = 100.00 %.
pub const THROTTLE_FULL_SCALE: u16 = 10_000;

/// Throttle fraction (0..1) from the wire level (0..10000). Values above full scale are kept
/// (the caller decides whether they are an error).
pub fn throttle_fraction(level: u16) -> f64 {
    level as f64 / THROTTLE_FULL_SCALE as f64
}

/// Wire level (0..10000) from a throttle fraction, rounded, clamped to 0..=10000 (NaN → 0).
pub fn throttle_level(fraction: f64) -> u16 {
    let v = (fraction * THROTTLE_FULL_SCALE as f64).round();
    if v.is_nan() || v <= 0.0 {
        0
    } else if v >= THROTTLE_FULL_SCALE as f64 {
        THROTTLE_FULL_SCALE
    } else {
        v as u16
    }
}

/// 0x42 SAMPLE: one per sample period.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sample {
    /// +1 per sample taken; a jump is a device-side drop.
    pub sample_index: u32,
    /// Device clock at the ADC instant, µs (wraps every 2³² µs ≈ 71.6 min).
    pub t_us: u32,
    /// Throttle applied during this sample period, 0..10000.
    pub throttle: u16,
    /// Flags, see [`SampleFlags`].
    pub flags: SampleFlags,
    /// Thrust, N.
    pub thrust_n: f32,
    /// Torque, N·m.
    pub torque_nm: f32,
    /// Rotor speed, rev/min (mechanical).
    pub rpm: f32,
    /// Supply voltage, V.
    pub voltage_v: f32,
    /// Current, A.
    pub current_a: f32,
}

impl Sample {
    /// Applied throttle as a fraction 0..1.
    pub fn throttle_fraction(&self) -> f64 {
        throttle_fraction(self.throttle)
    }

    /// True when the motor is armed.
    pub fn is_armed(&self) -> bool {
        self.flags.contains(SampleFlags::ARMED)
    }

    /// The value when its `*_VALID` flag is set, else `None`.
    fn valid(&self, flag: SampleFlags, v: f32) -> Option<f32> {
        self.flags.contains(flag).then_some(v)
    }

    /// Thrust (N) if valid.
    pub fn thrust(&self) -> Option<f32> {
        self.valid(SampleFlags::THRUST_VALID, self.thrust_n)
    }

    /// Torque (N·m) if valid.
    pub fn torque(&self) -> Option<f32> {
        self.valid(SampleFlags::TORQUE_VALID, self.torque_nm)
    }

    /// Rotor speed (rev/min) if valid.
    pub fn rotor_rpm(&self) -> Option<f32> {
        self.valid(SampleFlags::RPM_VALID, self.rpm)
    }

    /// Supply voltage (V) if valid.
    pub fn voltage(&self) -> Option<f32> {
        self.valid(SampleFlags::VOLTAGE_VALID, self.voltage_v)
    }

    /// Current (A) if valid.
    pub fn current(&self) -> Option<f32> {
        self.valid(SampleFlags::CURRENT_VALID, self.current_a)
    }
}

/// ACK result code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum AckResult {
    /// 0: done.
    Ok,
    /// 1: not allowed in this state.
    BadState,
    /// 2: an argument is out of range.
    OutOfRange,
    /// 3: unknown command type.
    UnknownType,
    /// 4: payload too short.
    BadLength,
    /// 5: wrong ARM key.
    BadKey,
    /// 6: a pulse or ramp is running.
    Busy,
    /// 7: a limit is active.
    LimitActive,
    /// 8: protocol version not supported.
    Version,
    /// A code this version does not know.
    Other(u8),
}

impl AckResult {
    /// From the wire code.
    pub fn from_u8(v: u8) -> Self {
        match v {
            0 => Self::Ok,
            1 => Self::BadState,
            2 => Self::OutOfRange,
            3 => Self::UnknownType,
            4 => Self::BadLength,
            5 => Self::BadKey,
            6 => Self::Busy,
            7 => Self::LimitActive,
            8 => Self::Version,
            o => Self::Other(o),
        }
    }

    /// The wire code.
    pub fn to_u8(self) -> u8 {
        match self {
            Self::Ok => 0,
            Self::BadState => 1,
            Self::OutOfRange => 2,
            Self::UnknownType => 3,
            Self::BadLength => 4,
            Self::BadKey => 5,
            Self::Busy => 6,
            Self::LimitActive => 7,
            Self::Version => 8,
            Self::Other(o) => o,
        }
    }
}

/// ACK flag bit0: a repeated command, answered from memory, not executed again.
pub const ACK_DUPLICATE: u8 = 1 << 0;

/// 0x43 ACK: answers every command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ack {
    /// `seq` of the command answered.
    pub cmd_seq: u16,
    /// Type of the command answered.
    pub cmd_type: u8,
    /// Outcome.
    pub result: AckResult,
    /// Flags, see [`ACK_DUPLICATE`].
    pub ack_flags: u8,
    /// When the command took effect or was refused (device clock, µs).
    pub t_us: u32,
}

impl Ack {
    /// True when this answers a repeated command.
    pub fn is_duplicate(&self) -> bool {
        self.ack_flags & ACK_DUPLICATE != 0
    }
}

/// EVENT code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum EventCode {
    /// 1: first sample of a device-timed pulse.
    ImpulseStart,
    /// 2: first sample after the pulse.
    ImpulseEnd,
    /// 3: the watchdog stopped the motor.
    WatchdogTrip,
    /// 4: a limit cut the motor off (`arg` = channel).
    LimitCutoff,
    /// 5: armed.
    Armed,
    /// 6: disarmed.
    Disarmed,
    /// 7: the device dropped samples (`arg` = how many).
    TxOverrun,
    /// 8: reset cause after boot.
    ResetCause,
    /// 9: tare finished.
    TareDone,
    /// A code this version does not know.
    Other(u8),
}

impl EventCode {
    /// From the wire code.
    pub fn from_u8(v: u8) -> Self {
        match v {
            1 => Self::ImpulseStart,
            2 => Self::ImpulseEnd,
            3 => Self::WatchdogTrip,
            4 => Self::LimitCutoff,
            5 => Self::Armed,
            6 => Self::Disarmed,
            7 => Self::TxOverrun,
            8 => Self::ResetCause,
            9 => Self::TareDone,
            o => Self::Other(o),
        }
    }

    /// The wire code.
    pub fn to_u8(self) -> u8 {
        match self {
            Self::ImpulseStart => 1,
            Self::ImpulseEnd => 2,
            Self::WatchdogTrip => 3,
            Self::LimitCutoff => 4,
            Self::Armed => 5,
            Self::Disarmed => 6,
            Self::TxOverrun => 7,
            Self::ResetCause => 8,
            Self::TareDone => 9,
            Self::Other(o) => o,
        }
    }
}

/// 0x44 EVENT.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Event {
    /// What happened.
    pub code: EventCode,
    /// Code-specific argument.
    pub arg: u16,
    /// Device clock, µs.
    pub t_us: u32,
    /// Exact sample index (impulse edges: the first sample inside / after the pulse).
    pub sample_index: u32,
}

/// Longest LOG text, bytes.
pub const LOG_TEXT_MAX: usize = 200;

/// 0x45 LOG: firmware debug text, fixed capacity (no allocation).
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Log {
    /// Severity (firmware-defined; 0 = most severe by convention).
    pub severity: u8,
    len: u8,
    text: [u8; LOG_TEXT_MAX],
}

impl Log {
    /// A LOG message; text beyond 200 bytes is cut at a char boundary.
    pub fn new(severity: u8, text: &str) -> Self {
        let cut = floor_char_boundary(text, LOG_TEXT_MAX);
        Self::from_bytes(severity, &text.as_bytes()[..cut])
    }

    /// A LOG message from raw bytes (cut to 200 bytes).
    pub fn from_bytes(severity: u8, bytes: &[u8]) -> Self {
        let n = bytes.len().min(LOG_TEXT_MAX);
        let mut text = [0u8; LOG_TEXT_MAX];
        text[..n].copy_from_slice(&bytes[..n]);
        Self {
            severity,
            len: n as u8,
            text,
        }
    }

    /// The raw text bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.text[..self.len as usize]
    }

    /// The text, cut before the first invalid UTF-8 byte.
    pub fn text(&self) -> &str {
        utf8_prefix(self.bytes())
    }
}

impl std::fmt::Debug for Log {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Log")
            .field("severity", &self.severity)
            .field("text", &self.text())
            .finish()
    }
}

/// The ARM key, bytes "ARM!" read little-endian.
pub const ARM_KEY: u32 = 0x214D_5241;

/// 0x02 ARM.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Arm {
    /// Watchdog, ms (100..5000).
    pub watchdog_ms: u16,
    /// Must be [`ARM_KEY`].
    pub key: u32,
}

impl Arm {
    /// ARM with the right key.
    pub fn new(watchdog_ms: u16) -> Self {
        Self {
            watchdog_ms,
            key: ARM_KEY,
        }
    }
}

/// 0x04 SET_THROTTLE.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SetThrottle {
    /// Level 0..10000.
    pub level: u16,
    /// Ramp duration, ms (0 = step).
    pub ramp_ms: u16,
}

/// 0x05 IMPULSE.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Impulse {
    /// Absolute pulse level 0..10000 (below the setpoint: a negative pulse).
    pub level: u16,
    /// Pulse width, µs.
    pub width_us: u32,
}

/// 0x08 SET_RATE.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SetRate {
    /// New nominal sample rate, Hz.
    pub sample_rate_hz: u16,
}

/// Any TSP/1 message, device → host or host → device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Message {
    /// 0x41.
    Hello(Hello),
    /// 0x42.
    Sample(Sample),
    /// 0x43.
    Ack(Ack),
    /// 0x44.
    Event(Event),
    /// 0x45.
    Log(Log),
    /// 0x01.
    HelloReq,
    /// 0x02.
    Arm(Arm),
    /// 0x03.
    Disarm,
    /// 0x04.
    SetThrottle(SetThrottle),
    /// 0x05.
    Impulse(Impulse),
    /// 0x06.
    Stop,
    /// 0x07.
    Heartbeat,
    /// 0x08.
    SetRate(SetRate),
    /// 0x09.
    Tare,
}

impl Message {
    /// The wire type code.
    pub fn msg_type(&self) -> u8 {
        use msg_type as t;
        match self {
            Self::Hello(_) => t::HELLO,
            Self::Sample(_) => t::SAMPLE,
            Self::Ack(_) => t::ACK,
            Self::Event(_) => t::EVENT,
            Self::Log(_) => t::LOG,
            Self::HelloReq => t::HELLO_REQ,
            Self::Arm(_) => t::ARM,
            Self::Disarm => t::DISARM,
            Self::SetThrottle(_) => t::SET_THROTTLE,
            Self::Impulse(_) => t::IMPULSE,
            Self::Stop => t::STOP,
            Self::Heartbeat => t::HEARTBEAT,
            Self::SetRate(_) => t::SET_RATE,
            Self::Tare => t::TARE,
        }
    }

    /// True for host → device messages (type 0x01..=0x3F).
    pub fn is_command(&self) -> bool {
        is_command_type(self.msg_type())
    }

    /// Protocol name of the message type (`"SAMPLE"`, `"SET_THROTTLE"`, …).
    pub fn name(&self) -> &'static str {
        type_name(self.msg_type()).unwrap_or("?")
    }
}

/// True for the host → device type range 0x01..=0x3F.
pub fn is_command_type(t: u8) -> bool {
    (0x01..=0x3F).contains(&t)
}

/// Protocol name of a known type code.
pub fn type_name(t: u8) -> Option<&'static str> {
    use msg_type as m;
    Some(match t {
        m::HELLO_REQ => "HELLO_REQ",
        m::ARM => "ARM",
        m::DISARM => "DISARM",
        m::SET_THROTTLE => "SET_THROTTLE",
        m::IMPULSE => "IMPULSE",
        m::STOP => "STOP",
        m::HEARTBEAT => "HEARTBEAT",
        m::SET_RATE => "SET_RATE",
        m::TARE => "TARE",
        m::HELLO => "HELLO",
        m::SAMPLE => "SAMPLE",
        m::ACK => "ACK",
        m::EVENT => "EVENT",
        m::LOG => "LOG",
        _ => return None,
    })
}

/// A decoded frame: the sender's link sequence number and the message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Per-sender counter (for commands also the command id).
    pub seq: u16,
    /// The message.
    pub msg: Message,
}

/// The longest prefix of `b` that is valid UTF-8.
fn utf8_prefix(b: &[u8]) -> &str {
    match std::str::from_utf8(b) {
        Ok(s) => s,
        // `valid_up_to` is a char boundary, so this inner conversion cannot fail.
        Err(e) => std::str::from_utf8(&b[..e.valid_up_to()]).unwrap_or(""),
    }
}

/// Largest index `<= max` that is a char boundary of `s`.
fn floor_char_boundary(s: &str, max: usize) -> usize {
    if s.len() <= max {
        return s.len();
    }
    (0..=max)
        .rev()
        .find(|&i| s.is_char_boundary(i))
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip() {
        for v in 0..=255u8 {
            assert_eq!(AckResult::from_u8(v).to_u8(), v);
            assert_eq!(EventCode::from_u8(v).to_u8(), v);
            assert_eq!(EscProtocol::from_u8(v).to_u8(), v);
        }
        assert_eq!(AckResult::from_u8(6), AckResult::Busy);
        assert_eq!(EventCode::from_u8(2), EventCode::ImpulseEnd);
    }

    #[test]
    fn arm_key_is_ascii_arm_bang() {
        assert_eq!(ARM_KEY.to_le_bytes(), *b"ARM!");
    }

    #[test]
    fn throttle_conversions() {
        assert_eq!(throttle_fraction(3500), 0.35);
        assert_eq!(throttle_level(0.35), 3500);
        assert_eq!(throttle_level(-1.0), 0);
        assert_eq!(throttle_level(2.0), 10_000);
        assert_eq!(throttle_level(f64::NAN), 0);
    }

    #[test]
    fn sample_flag_helpers() {
        let s = Sample {
            flags: SampleFlags::ARMED | SampleFlags::THRUST_VALID,
            thrust_n: 1.5,
            rpm: 100.0,
            ..Sample::default()
        };
        assert!(s.is_armed());
        assert_eq!(s.thrust(), Some(1.5));
        assert_eq!(s.rotor_rpm(), None);
        let mut f = s.flags;
        f.remove(SampleFlags::ARMED);
        f.insert(SampleFlags::RPM_VALID);
        assert_eq!(f.bits(), 0b1010);
    }

    #[test]
    fn hello_channels_are_flags_shifted_right() {
        let h = Hello {
            proto_minor: 0,
            esc_protocol: EscProtocol::DShot600,
            fw_version: 1,
            boot_id: 7,
            t_us: 0,
            sample_rate_hz: 1000,
            channels: 0b00101, // thrust, rpm
            motor_poles: 14,
            caps: caps::IMPULSE | caps::TARE,
            name: Hello::name_field("stand"),
        };
        assert!(h.has_channel(SampleFlags::THRUST_VALID));
        assert!(!h.has_channel(SampleFlags::TORQUE_VALID));
        assert!(h.has_channel(SampleFlags::RPM_VALID));
        assert!(h.has_cap(caps::TARE) && !h.has_cap(caps::RAMP));
        assert_eq!(h.name_str(), "stand");
    }

    #[test]
    fn log_text_is_cut_at_char_boundary() {
        let long = "é".repeat(150); // 300 bytes
        let log = Log::new(2, &long);
        assert_eq!(log.bytes().len(), 200);
        assert_eq!(log.text().chars().count(), 100);
        let bad = Log::from_bytes(1, &[b'o', b'k', 0xFF, b'x']);
        assert_eq!(bad.text(), "ok");
    }
}
