//! `Track`: keys inserted in time order, easings, moving and removing keys, sanity.

use lapclone::scene::{Easing, KeyError, Track};

#[test]
fn easing_endpoints() {
    for e in Easing::ALL {
        assert_eq!(e.apply(1.0), 1.0, "{e:?}");
        assert_eq!(e.apply(0.0), 0.0, "{e:?}");
        assert_eq!(Easing::from_name(e.name()), Some(e));
    }
}

#[test]
fn keys_insert_in_order_and_replace_at_equal_times() {
    let mut t = Track::<f64>::new();
    t.push(1.0, 0.0, Easing::Linear).unwrap();
    t.push(3.0, 3.0, Easing::Linear).unwrap();
    t.push(0.5, 1.0, Easing::Smooth).unwrap();
    assert_eq!(t.times().collect::<Vec<_>>(), [0.5, 1.0, 3.0]);
    t.push(1.0, 7.0, Easing::Hold).unwrap();
    assert_eq!(t.keys().len(), 3);
    assert_eq!(t.keys()[1].value, 7.0);
    assert_eq!(t.keys()[1].easing, Easing::Hold);
    assert!(t.sanity_check().is_ok());
    assert!(matches!(
        t.push(-1.0, 0.0, Easing::Linear),
        Err(KeyError::NegativeTime(_))
    ));
    assert!(matches!(
        t.push(f64::NAN, 0.0, Easing::Linear),
        Err(KeyError::NonFiniteTime(_))
    ));
    assert_eq!(t.keys().len(), 3);
}

#[test]
fn remove_and_move_find_exact_times() {
    let mut t = Track::<f64>::new();
    for (time, v) in [(0.0, 0.0), (1.5, 1.0), (3.0, 2.0)] {
        t.push(time, v, Easing::Linear).unwrap();
    }
    assert!(t.remove(1.5000001).is_none());
    assert_eq!(t.remove(1.5).map(|k| k.value), Some(1.0));
    assert!(t.move_key(3.0, 0.5));
    assert_eq!(t.times().collect::<Vec<_>>(), [0.0, 0.5]);
    assert!(!t.move_key(2.0, 1.0));
    assert!(!t.move_key(0.5, -1.0));
    assert_eq!(t.times().collect::<Vec<_>>(), [0.0, 0.5]);
}
