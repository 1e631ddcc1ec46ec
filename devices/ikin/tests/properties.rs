//! Generic chains from iKin's links properties.

use icub_ikin::nalgebra::Matrix4;
use icub_ikin::properties::{from_links_properties, to_links_properties};
use icub_ikin::{KinError, Limb, DEG2RAD};
use yarp_proto::Property;

const CONFIG: &str = "\
type left
H0 (0 -1 0 0  0 0 -1 0  1 0 0 0  0 0 0 1)
numLinks 3
link_0 (A 0.1) (D 0.02) (alpha 90.0) (offset -90.0) (min -45) (max 45)
link_1 (A 0.2) (blocked 10.0)
link_2 (A 0.05) (alpha -90)
";

#[test]
fn parses_ikin_links_format() {
    let p = Property::from_config_text(CONFIG).unwrap();
    let d = from_links_properties(&p).unwrap();
    assert_eq!(d.type_name, "left");
    let c = &d.chain;
    assert_eq!((c.n(), c.dof()), (3, 2));
    let l0 = c.link(0).unwrap();
    assert_eq!((l0.a, l0.d), (0.1, 0.02));
    assert!((l0.alpha - 90.0 * DEG2RAD).abs() < 1e-15);
    assert!((l0.offset + 90.0 * DEG2RAD).abs() < 1e-15);
    assert!((l0.min + 45.0 * DEG2RAD).abs() < 1e-15);
    // Defaults: ±180 degrees bounds, zero parameters.
    let l1 = c.link(1).unwrap();
    assert!((l1.max - 180.0 * DEG2RAD).abs() < 1e-12 && l1.d == 0.0);
    assert!((c.link_ang(1).unwrap() - 10.0 * DEG2RAD).abs() < 1e-12);
    assert_eq!(c.h0()[(0, 1)], -1.0);
    assert_eq!(*c.hn(), Matrix4::identity());
}

#[test]
fn round_trips_an_icub_limb() {
    let arm = Limb::arm("right_v2.5").unwrap();
    let p = to_links_properties(arm.type_name(), arm.chain());
    // Through text too, as a config file would carry it.
    let text = String::from_utf8(p.to_text()).unwrap();
    let back = from_links_properties(&Property::from_text(&text)).unwrap();
    assert_eq!(back.type_name, "right_v2.5");
    assert_eq!(back.chain.n(), 10);
    assert_eq!(back.chain.dof(), 7);
    for (a, b) in arm.chain().links().iter().zip(back.chain.links()) {
        for (x, y) in [
            (a.a, b.a),
            (a.d, b.d),
            (a.alpha, b.alpha),
            (a.offset, b.offset),
        ] {
            assert!((x - y).abs() < 1e-12);
        }
    }
    let q = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.0];
    let d = (arm.chain().h_at(&q).unwrap() - back.chain.h_at(&q).unwrap()).amax();
    assert!(d < 1e-12);
}

#[test]
fn malformed_descriptions_are_errors() {
    for (text, what) in [
        ("type right", "numLinks"),
        ("numLinks 2\nlink_0 (A 0.1)", "link_1"),
        ("numLinks 1\nlink_0 (A foo)", "A"),
        ("numLinks 1\nH0 3\nlink_0 (A 0.1)", "H0"),
    ] {
        let err = from_links_properties(&Property::from_config_text(text).unwrap()).unwrap_err();
        assert!(matches!(err, KinError::Properties(_)), "{text}: {err:?}");
        assert!(err.to_string().contains(what), "{err}");
    }
    let p = Property::from_config_text("numLinks 1\nlink_0 (min 10) (max -10)").unwrap();
    assert!(matches!(
        from_links_properties(&p),
        Err(KinError::InvalidBounds { .. })
    ));
}
