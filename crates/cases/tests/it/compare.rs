//! Two plans of one patient compared: figures side by side and the difference map.

use tissue_cases::{CaseError, Library};

use crate::common::{save, table2, table2_single, Tmp};

#[test]
fn two_volumes_compare_in_the_right_direction_with_the_exact_difference_map() {
    let tmp = Tmp::new("compare");
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let (_, scan) = table2();
    let (spec_a, small) = table2_single(60.0, 80);
    let (spec_b, large) = table2_single(120.0, 80);
    let a = save(&lib, &scan, "60", &spec_a, &small);
    let b = save(&lib, &scan, "120", &spec_b, &large);
    let cmp = lib.compare(&a.uid, &b.uid).unwrap();
    assert_eq!(
        (cmp.a.uid.as_str(), cmp.b.uid.as_str()),
        (a.uid.as_str(), b.uid.as_str())
    );
    let row = |name: &str| {
        cmp.figures
            .iter()
            .find(|r| r.name == name)
            .unwrap_or_else(|| panic!("no figure {name}"))
            .clone()
    };
    for name in [
        "area_gain_cm2",
        "implant_volume_cm3",
        "volume_difference_cm3",
        "steps",
        "wall_time_s",
    ] {
        let r = row(name);
        assert!(r.a.is_some() && r.b.is_some(), "{name}");
        assert_eq!(r.difference, Some(r.b.unwrap() - r.a.unwrap()));
    }
    assert!(row("implant_volume_cm3").difference.unwrap() > 0.0);
    assert!(row("area_gain_cm2").difference.unwrap() > 0.0);
    assert!(!cmp.figures.iter().any(|r| r.name == "schema_version"));

    let (ra, rb) = (small.patient.unwrap(), large.patient.unwrap());
    assert_eq!(cmp.difference.len(), ra.after.positions().len());
    let mut max = 0.0f32;
    for (i, d) in cmp.difference.iter().enumerate() {
        let by_hand = (rb.after.positions()[i] - ra.after.positions()[i]).length();
        assert_eq!(d.to_bits(), by_hand.to_bits(), "vertex {i}");
        if ra.in_region[i] == 0.0 && rb.in_region[i] == 0.0 {
            assert_eq!(*d, 0.0, "vertex {i} outside both regions moved");
        }
        max = max.max(by_hand);
    }
    assert!(max > 0.0);
    assert_eq!(cmp.max_difference, max);

    // Plans of two patients are refused.
    let (chest_scan, chest_spec, chest) = crate::common::chest_single(40);
    let c = save(&lib, &chest_scan, "chest", &chest_spec, &chest);
    assert!(matches!(
        lib.compare(&a.uid, &c.uid),
        Err(CaseError::Invalid { field: "b", .. })
    ));
}
