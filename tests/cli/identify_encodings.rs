//! Exports in the encodings a PC writes (`propid_wire::protocol::csv::encoding`): the Tyto
//! Series 1585 dialect (`ESC signal (µs)`, `Torque (N·m)`) saved as Windows-1252 (Excel's
//! "CSV", `µ` the byte `B5`), as UTF-16 with a byte order mark (Excel's "Unicode text", tab
//! separated) or without one, and as UTF-32 is read exactly as its UTF-8 original, and the
//! encoding is stated.

use propid_testkit::dialects::dialects;
use serde_json::Value;

use crate::support::propid;

fn identify(path: &std::path::Path) -> Value {
    let (code, out, err) = propid(&["identify", path.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{}: {err}", path.display());
    serde_json::from_str(&out).unwrap()
}

#[test]
fn windows_1252_and_utf16_exports_read_as_their_utf8_original() {
    let text = dialects()
        .into_iter()
        .find(|d| d.name == "tyto_1585_kgf")
        .expect("the Tyto 1585 dialect")
        .text;
    assert!(text.contains('µ') && text.contains('·'));
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str, bytes: Vec<u8>| {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    let utf8 = identify(&file("utf8.csv", text.clone().into_bytes()));
    assert!(utf8["source"]["csv"].get("encoding").is_none());
    let cp1252: Vec<u8> = text
        .chars()
        .map(|c| match c {
            'µ' => 0xB5,
            '·' => 0xB7,
            c if c.is_ascii() => c as u8,
            c => panic!("{c:?} is not in the test's table"),
        })
        .collect();
    let tabbed = text.replace(',', "\t");
    let mut le = vec![0xFF, 0xFE];
    let mut be = vec![0xFE, 0xFF];
    for u in tabbed.encode_utf16() {
        le.extend(u.to_le_bytes());
        be.extend(u.to_be_bytes());
    }
    // Without their byte order mark (told by the NUL bytes of ASCII text), and UTF-32.
    let (le_bare, be_bare) = (le[2..].to_vec(), be[2..].to_vec());
    let (mut le32, mut be32) = (Vec::new(), Vec::new());
    for c in tabbed.chars() {
        le32.extend((c as u32).to_le_bytes());
        be32.extend((c as u32).to_be_bytes());
    }
    for (name, bytes, encoding) in [
        ("cp1252.csv", cp1252, "windows-1252"),
        ("utf16le.txt", le, "utf-16le"),
        ("utf16be.txt", be, "utf-16be"),
        ("utf16le-no-bom.txt", le_bare, "utf-16le"),
        ("utf16be-no-bom.txt", be_bare, "utf-16be"),
        ("utf32le.txt", le32, "utf-32le"),
        ("utf32be.txt", be32, "utf-32be"),
    ] {
        let v = identify(&file(name, bytes));
        let s = &v["source"];
        assert_eq!(s["csv"]["encoding"], encoding, "{name}");
        assert_eq!(s["units"], utf8["source"]["units"], "{name}");
        assert_eq!(s["input_range"], utf8["source"]["input_range"], "{name}");
        assert_eq!(v["model"]["dc_gain"], utf8["model"]["dc_gain"], "{name}");
        assert_eq!(v["steps"], utf8["steps"], "{name}");
    }
}
