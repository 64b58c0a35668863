//! Bad input gets an error naming the file, the line and the field; never a panic.

use std::path::PathBuf;

use thermokin_io::{IoError, parse_robot_toml, read_deviation_table, read_targets, read_temperature_log};

fn write(name: &str, content: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thermokin-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, content).unwrap();
    p
}

/// The rendered message, checked to name the file and (when given) the line and field.
fn located(err: IoError, file: &str, line: Option<usize>, field: &str) -> String {
    let msg = err.to_string();
    assert!(msg.contains(file), "no file in: {msg}");
    if let Some(l) = line {
        assert!(msg.contains(&format!(":{l}:")), "no line {l} in: {msg}");
    }
    assert!(msg.contains(field), "no field `{field}` in: {msg}");
    msg
}

const GOOD_JOINT: &str = "[[joint]]\naxis = \"Z\"\noffset_mm = [0.0, 0.0, 100.0]\n";

#[test]
fn robot_toml_errors() {
    let p = PathBuf::from("robot.toml");
    let cases: &[(&str, Option<usize>, &str, &str)] = &[
        // unknown key, with its line
        (&format!("{GOOD_JOINT}colour = \"red\"\n"), Some(4), "colour", "unknown field"),
        // a zero axis
        (
            "[[joint]]\naxis = [0.0, 0.0, 0.0]\noffset_mm = [0.0, 0.0, 1.0]\n",
            Some(1),
            "joint[1].axis",
            "not a usable axis",
        ),
        // a bad axis name
        ("[[joint]]\naxis = \"W\"\noffset_mm = [0.0, 0.0, 1.0]\n", Some(1), "joint[1].axis", "not an axis"),
        // NaN
        ("[[joint]]\naxis = \"X\"\noffset_mm = [nan, 0.0, 1.0]\n", Some(1), "joint[1].offset_mm", "finite"),
        // inf in the tool
        (&format!("{GOOD_JOINT}[tool]\ntranslation_mm = [inf, 0.0, 0.0]\n"), Some(4), "tool.translation_mm", "finite"),
        // limits reversed
        (
            "[[joint]]\naxis = \"X\"\noffset_mm = [0.0, 0.0, 1.0]\nlimits = [10.0, -10.0]\n",
            Some(1),
            "joint[1].limits",
            "above",
        ),
        // missing required key
        ("[[joint]]\naxis = \"X\"\n", Some(1), "offset_mm", "missing field"),
        // a string where a number belongs
        ("[[joint]]\naxis = \"X\"\noffset_mm = [\"a\", 0.0, 1.0]\n", Some(3), "toml", "invalid type"),
        // truncated file
        ("[[joint]]\naxis = \"X\"\noffset_mm = [0.0, 0.0", Some(3), "toml", ""),
        // no joints at all
        ("name = \"x\"\n", None, "joint", "no [[joint]] rows"),
        // DH rows under the extended convention
        ("[[dh]]\na_mm = 1.0\nalpha_deg = 0.0\nd_mm = 0.0\n", Some(1), "dh", "convention"),
    ];
    for (text, line, field, needle) in cases {
        let err = parse_robot_toml(&p, text).expect_err(text);
        let msg = located(err, "robot.toml", *line, field);
        assert!(msg.contains(needle), "`{needle}` not in: {msg}");
    }
}

#[test]
fn deviation_csv_errors() {
    let cases: &[(&str, &[u8], Option<usize>, &str, &str)] = &[
        ("empty.csv", b"", Some(1), "header", "empty file"),
        ("cols.csv", b"Dx,Dy,Dz,Dox,Doy,Doz\r\n1,2,3,4,5\r\n", Some(2), "row", "5 fields"),
        ("extra.csv", b"Dx,Dy,Dz,Dox,Doy,Doz\n1,2,3,4,5,6,7\n", Some(2), "row", "7 fields"),
        ("nan.csv", b"Dx,Dy,Dz,Dox,Doy,Doz\n1,2,3,4,5,6\n1,NaN,3,4,5,6\n", Some(3), "Dy", "not a finite"),
        ("text.csv", b"Dx,Dy,Dz,Dox,Doy,Doz\n1,2,x,4,5,6\n", Some(2), "Dz", "not a number"),
        ("header.csv", b"Dx,Dy,Dz,Dox,Doy\n1,2,3,4,5\n", Some(1), "Doz", "missing column"),
        ("semi.csv", b"Dx;Dy;Dz;Dox;Doy;Doz\n1;2;3;4;5;6\n", Some(1), "delimiter", "';'"),
        ("latin1.csv", b"Dx,Dy,Dz,Dox,Doy,Doz\n1,2,3,4,5,6\n\xe9,2,3,4,5,6\n", Some(3), "text", "not UTF-8"),
        ("norows.csv", b"Dx,Dy,Dz,Dox,Doy,Doz\n", Some(2), "rows", "no joint rows"),
        ("overflow.csv", b"Dx,Dy,Dz,Dox,Doy,Doz\n1e999,0,0,0,0,0\n", Some(2), "Dx", "not a finite"),
    ];
    for (name, content, line, field, needle) in cases {
        let p = write(name, content);
        let err = read_deviation_table(&p).expect_err(name);
        let msg = located(err, name, *line, field);
        assert!(msg.contains(needle), "`{needle}` not in: {msg}");
    }
    // A byte-order mark and mixed line endings are fine.
    let p = write("bom.csv", b"\xef\xbb\xbfDx,Dy,Dz,Dox,Doy,Doz\r\n1,2,3,4,5,6\n0,0,0,0,0,0\r\n");
    assert_eq!(read_deviation_table(&p).unwrap().dof(), 2);
    // Rows ≠ joints.
    let err = thermokin_io::read_deviation_table_for(&p, 6).unwrap_err();
    located(err, "bom.csv", None, "rows");
}

#[test]
fn targets_and_log_errors() {
    let p = write("t1.csv", b",X,Y\nP1,1,2\n");
    located(read_targets(&p).unwrap_err(), "t1.csv", Some(1), "Z");
    let p = write("t2.csv", b",X,Y,Z,RX,RY\nP1,1,2,3,0,90\n");
    located(read_targets(&p).unwrap_err(), "t2.csv", Some(1), "RX,RY,RZ");
    let p = write("t3.csv", b",X,Y,Z\nP1,1,2,3\nP2,1,inf,3\n");
    located(read_targets(&p).unwrap_err(), "t3.csv", Some(3), "Y");
    let p = write("t4.csv", b",X,Y,Z\nP1,1,2\n");
    located(read_targets(&p).unwrap_err(), "t4.csv", Some(2), "row");
    let p = write("log1.csv", b"time_min,temp_a\n0,20\n0,21\n");
    located(read_temperature_log(&p).unwrap_err(), "log1.csv", Some(3), "time_min");
    let p = write("log2.csv", b"t,temp_a\n0,20\n");
    located(read_temperature_log(&p).unwrap_err(), "log2.csv", Some(1), "time_min");
    let p = std::env::temp_dir().join("thermokin-no-such-dir").join("none.csv");
    assert!(read_targets(&p).unwrap_err().to_string().contains("none.csv"));
}
