use super::*;
use propid_wire::protocol::message::{Hello, Sample, SampleFlags};
use propid_wire::protocol::{encode_frame, EscProtocol, Message, MAX_FRAME_LEN};

fn wire(seq: u16, m: &Message, out: &mut Vec<u8>) {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(seq, m, &mut buf);
    out.extend_from_slice(&buf[..n]);
}

fn recording(n: u32) -> Vec<u8> {
    let mut out = b"boot v1.0\r\n".to_vec();
    out.push(0);
    let hello = Hello {
        proto_minor: 0,
        esc_protocol: EscProtocol::DShot600,
        fw_version: 1,
        boot_id: 9,
        t_us: 0,
        sample_rate_hz: 500,
        channels: 0x01,
        motor_poles: 0,
        caps: 0,
        name: Hello::name_field("t"),
    };
    wire(0, &Message::Hello(hello), &mut out);
    for i in 0..n {
        let s = Sample {
            sample_index: i,
            t_us: 2000 * i,
            throttle: 1000,
            flags: SampleFlags::THRUST_VALID,
            thrust_n: 0.5 * i as f32,
            ..Sample::default()
        };
        wire(i as u16 + 1, &Message::Sample(s), &mut out);
    }
    out
}

#[test]
fn binary_recording_to_record() {
    let bytes = recording(50);
    let (r, s) = read_record(&bytes).unwrap();
    assert_eq!(s.format, WireFormat::Binary);
    assert_eq!(r.len(), 50);
    assert_eq!(r.dt_s, 2e-3);
    assert_eq!(s.dt_nominal_s, Some(2e-3));
    assert_eq!(r.channel("thrust_N").unwrap().data[10], 5.0);
    let frames = s.frames.unwrap();
    assert_eq!(frames.frames_ok, 51);
    assert_eq!(frames.dropped.total(), 1); // the banner
}

#[test]
fn csv_stream_with_index_and_gaps() {
    let text = "# bench\nt_us,idx,throttle,thrust_N\n0,0,1000,1\n1000,1,1000,2\n4000,4,1000,3\n";
    let (r, s) = read_record(text.as_bytes()).unwrap();
    assert_eq!(s.format, WireFormat::Csv);
    assert_eq!(r.len(), 5);
    assert_eq!(r.missing, [false, false, true, true, false]);
    assert_eq!(r.dt_s, 1e-3);
    assert_eq!(s.assemble.samples_lost, 2);
    assert_eq!(r.channel("throttle").unwrap().data[0], 0.1);
}

#[test]
fn headerless_csv_on_a_time_grid() {
    let text = "0,5000,1.0\n10000,5000,1.5\n20000,5000,2.0\n40000,5000,2.5\n";
    let (r, s) = read_record(text.as_bytes()).unwrap();
    assert_eq!(r.len(), 5);
    assert_eq!(r.missing_count(), 1);
    assert!((r.dt_s - 0.01).abs() < 1e-12);
    assert_eq!(s.csv.unwrap().rows, 4);
}

#[test]
fn csv_without_time_needs_a_rate() {
    let text = "throttle_pct,thrust_N\n50,1\n50,2\n";
    assert_eq!(
        read_record(text.as_bytes()).unwrap_err(),
        IngestError::NoTimebase
    );
    let o = IngestOptions {
        fs_hz: Some(50.0),
        ..Default::default()
    };
    let (r, _) = read_record_with(text.as_bytes(), &o).unwrap();
    assert_eq!((r.len(), r.dt_s), (2, 0.02));
    assert_eq!(r.channel("throttle").unwrap().data[1], 0.5);
}

#[test]
fn csv_unit_that_needs_an_option_is_a_clear_error() {
    let text = "t_s,throttle_us,thrust_N\n0,1500,1\n0.1,1500,1\n";
    let e = read_record(text.as_bytes()).unwrap_err();
    assert!(matches!(e, IngestError::NeedsOption { ref column, .. } if column == "throttle_us"));
    assert!(e.to_string().contains("throttle_us"));
}

#[test]
fn typed_errors_for_empty_and_sample_free_input() {
    assert_eq!(read_record(b"").unwrap_err(), IngestError::Empty);
    assert_eq!(read_record(&[0, 0, 0]).unwrap_err(), IngestError::NoSamples);
    assert_eq!(
        read_record(b"# only a banner\n").unwrap_err(),
        IngestError::NoSamples
    );
    let mut only_hello = Vec::new();
    wire(0, &Message::HelloReq, &mut only_hello);
    assert_eq!(
        read_record(&only_hello).unwrap_err(),
        IngestError::NoSamples
    );
}

#[test]
fn a_recording_read_in_pieces_is_the_one_read_whole() {
    let mut bytes = recording(300);
    bytes.extend_from_slice(b"\x00garbage\x00"); // a skipped frame, counted either way
    bytes.extend_from_slice(&recording(20)[40..]);
    let whole = read_record(&bytes).unwrap();
    for piece in [1, 7, 64, 4096] {
        let mut r = BinaryReader::new(&IngestOptions::default());
        for c in bytes.chunks(piece) {
            r.push(c);
        }
        let pieces = r.finish().unwrap();
        assert_eq!(pieces.1, whole.1, "piece {piece}");
        // NaN (a missing sample) is no equal of itself: the records compared as printed
        let show = |r: &Record| format!("{r:?}");
        assert_eq!(show(&pieces.0), show(&whole.0), "piece {piece}");
    }
}
