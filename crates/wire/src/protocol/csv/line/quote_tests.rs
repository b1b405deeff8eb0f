//! Quoted fields, escaped quotes and stray quotes (rule 4 of the [line rules](super)).

use super::*;

fn split(line: &str, sep: char) -> Vec<String> {
    fields(line, sep).map(Cow::into_owned).collect()
}

#[test]
fn rfc_4180_escaped_quotes_and_separators_inside_a_quoted_field() {
    // `""` inside a quoted field is one `"`; the field keeps its separator.
    let header = "\"Time (s)\",\"Thrust \"\"gf\"\"\",\"Note, \"\"10x4.5\"\" prop\"";
    assert_eq!(separator(header), ',');
    assert_eq!(
        split(header, ','),
        ["Time (s)", "Thrust \"gf\"", "Note, \"10x4.5\" prop"]
    );
    // Plain quoted fields are borrowed from the line, escaped ones are not.
    let mut f = fields(header, ',');
    assert!(matches!(f.next(), Some(Cow::Borrowed("Time (s)"))));
    assert!(matches!(f.next(), Some(Cow::Owned(_))));
    // An empty quoted field, a quoted field that is one escaped quote, spaces around.
    assert_eq!(split("\"\", \"\"\"\" ,x", ','), ["", "\"", "x"]);
    // Blanks before the opening quote; a tab separator is not one.
    assert_eq!(split("\t\"a,b\" ,c", ','), ["a,b", "c"]);
    assert_eq!(split("\t\"a\tb\"\tc", '\t'), ["", "a\tb", "c"]);
    // Text after the closing quote is kept (lenient).
    assert_eq!(split("\"5\" prop,1", ','), ["5 prop", "1"]);
    // In a `;` file: the quoted `;` and the decimal commas stay.
    let eu = "\"Schub \"\"g\"\"; Zelle 1\";\"0,45\";12,3";
    assert_eq!(separator(eu), ';');
    assert_eq!(split(eu, ';'), ["Schub \"g\"; Zelle 1", "0,45", "12,3"]);
}

#[test]
fn a_stray_quote_is_an_ordinary_character_and_swallows_nothing() {
    // An inch mark inside a header or a cell: not at a field's start, not a quote.
    let header = "Time (s),Torque (in-oz\"),Throttle (%),Prop 5\"x4.5,Thrust (g)";
    assert_eq!(separator(header), ',');
    assert_eq!(
        split(header, ','),
        [
            "Time (s)",
            "Torque (in-oz\")",
            "Throttle (%)",
            "Prop 5\"x4.5",
            "Thrust (g)"
        ]
    );
    let row = "0.010,3.5,30.0,5\"x4.5,305.9";
    assert_eq!(
        split(row, ','),
        ["0.010", "3.5", "30.0", "5\"x4.5", "305.9"]
    );
    // A quote that opens a field and is never closed on the line: ordinary, to the separator.
    assert_eq!(split("\"10x4.5,30,305.9", ','), ["\"10x4.5", "30", "305.9"]);
    assert_eq!(split("a;\"b;c", ';'), ["a", "\"b", "c"]);
    // Two inch marks on a line do not pair up into a quoted span across fields.
    assert_eq!(
        split("Prop 5\"x4.5,12,Pitch 4.5\"", ','),
        ["Prop 5\"x4.5", "12", "Pitch 4.5\""]
    );
    // The separator of a line with inch marks: its commas count (the digits around a `"`
    // field do not hide them).
    assert_eq!(separator("5\"x4.5;0,45;12,3"), ';');
    assert_eq!(separator("Prop 5\"x4.5,Thrust (g);x"), ',');
    assert!(is_numeric("0,010;\"1,5\";", ';'));
}
