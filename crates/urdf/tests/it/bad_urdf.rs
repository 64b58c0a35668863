//! Malformed URDF, missing links, cycles, unsupported joints: errors naming the element.

use thermokin_urdf::{ImportOptions, import_urdf};

fn err(text: &str, opts: &ImportOptions) -> String {
    import_urdf(text, "bad.urdf", opts).map(|_| ()).expect_err(text).to_string()
}

const J: &str = r#"<joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="0" velocity="0"/></joint>"#;

#[test]
fn located_errors() {
    let d = ImportOptions::default();
    let cases: Vec<(String, ImportOptions, &str)> = vec![
        ("<robot name=\"r\"><link name=\"a\"/>".into(), d.clone(), "malformed URDF"),
        (format!("<robot name=\"r\"><link name=\"a\"/>{J}</robot>"), d.clone(), "<joint name=\"j1\">: its child link `b` does not exist"),
        (
            format!("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/>{J}{}</robot>", r#"<joint name="j2" type="fixed"><parent link="b"/><child link="a"/></joint>"#),
            d.clone(),
            "cycle",
        ),
        (
            r#"<robot name="r"><link name="a"/><link name="b"/><joint name="f" type="floating"><parent link="a"/><child link="b"/></joint></robot>"#.into(),
            d.clone(),
            "<joint name=\"f\">: joint type Floating is not supported",
        ),
        (
            r#"<robot name="r"><link name="a"/><link name="b"/><joint name="z" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 0"/></joint></robot>"#.into(),
            d.clone(),
            "<joint name=\"z\">: the axis is zero",
        ),
        (
            format!("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>{J}{}</robot>", r#"<joint name="j2" type="revolute"><parent link="a"/><child link="c"/><axis xyz="0 0 1"/></joint>"#),
            d.clone(),
            "the tip is ambiguous: leaves below `a` are b, c",
        ),
        (format!("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/>{J}</robot>"), ImportOptions { base: None, tip: Some("zz".into()) }, "tip link `zz` does not exist"),
        (
            r#"<robot name="r"><link name="a"/><link name="b"/><joint name="m" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/><mimic joint="x"/></joint></robot>"#.into(),
            ImportOptions { base: None, tip: Some("b".into()) },
            "mimic",
        ),
    ];
    for (text, opts, needle) in cases {
        let e = err(&text, &opts);
        assert!(e.contains(needle), "`{needle}` not in: {e}");
        assert!(e.starts_with("bad.urdf"), "{e}");
    }
}

#[test]
fn namespace_shapes_that_crashed_the_parser_are_errors() {
    // Found by fuzzing (docs/reliability.md): RustyXML, under urdf-rs, panicked on these.
    let d = ImportOptions::default();
    let e = err(r#"<robot name="r" xmlns:xmlns="http://example.invalid"><link name="a"/></robot>"#, &d);
    assert!(e.contains("the reserved prefix `xmlns` cannot be declared"), "{e}");
    let e = err(r#"<robot name="r"><link name="a" foo:bar="1"/></robot>"#, &d);
    assert!(e.contains("namespaced name `foo:bar` is not URDF"), "{e}");
    let e = err(r#"<robot name="r" xmlns="urn:x"><link name="a"/></robot>"#, &d);
    assert!(e.contains("a default XML namespace"), "{e}");
    // A declared prefix (xacro's, as in the ROS-Industrial files) is fine.
    let ok = r#"<robot name="r" xmlns:xacro="http://ros.org/wiki/xacro"><link name="a"/><link name="b"/><joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="0" velocity="0"/></joint></robot>"#;
    assert!(import_urdf(ok, "ok.urdf", &d).is_ok());
}

#[test]
fn multibyte_text_next_to_a_prefix_is_an_error_not_a_panic() {
    // Found by fuzzing: the namespace check itself sliced inside a multi-byte character.
    let d = ImportOptions::default();
    for text in
        ["<robot name=\"r\"><link name=\"a\" \u{e9}:b=\"1\"/></robot>", "<robot name=\"r\">\u{52356}o:x</robot>"]
    {
        assert!(import_urdf(text, "bad.urdf", &d).is_err());
    }
}

#[test]
fn empty_prefixes_and_unbound_uris_are_errors() {
    // Found by fuzzing: an attribute `:name` under a default namespace crashed RustyXML.
    let d = ImportOptions::default();
    let e = err(r#"<robot name="r"><link :name="a"/></robot>"#, &d);
    assert!(e.contains("malformed qualified name `:name`"), "{e}");
    let e = err(r#"<robot xmlns="0" name="r"><link name="a"/></robot>"#, &d);
    assert!(e.contains("a default XML namespace"), "{e}");
    let e = err(r#"<robot name="r" xmlns:p=""><link name="a" p:x="1"/></robot>"#, &d);
    assert!(e.contains("bound to an empty URI"), "{e}");
}
