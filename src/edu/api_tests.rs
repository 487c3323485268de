//! [`super`]'s tests: each call as spherov2 does it, and hostile numbers refused or bounded.

use super::*;

fn num(v: &[f64]) -> Vec<Arg> {
    v.iter().map(|x| Arg::Num(*x)).collect()
}

#[test]
fn roll_backward_turns_the_heading_and_drives_backward_as_spherov2_does() {
    let mut d = Driver::new(Model::Bolt);
    let e = d.call("roll", &num(&[90.0, -100.0, 1.0])).unwrap();
    assert_eq!(d.heading, 270);
    assert_eq!(
        e.now,
        vec![Act::Drive {
            speed: 100,
            heading: 90,
            reverse: true
        }]
    );
}

#[test]
fn mini_speeds_are_mapped() {
    let mut d = Driver::new(Model::Mini);
    d.call("setSpeed", &num(&[100.0])).unwrap();
    assert_eq!(d.speed, 151);
}

/// spherov2's `spin`: the heading of a step is a function of the time since the call,
/// rounded half to even, the first at 0 s turned 0°, the last the first to turn the whole
/// angle (sphero_edu.py `spin`).
#[test]
fn spin_steps_are_the_turn_at_the_time_they_are_made_and_end_on_the_whole_angle() {
    let mut d = Driver::new(Model::Bolt);
    d.heading = 10;
    let e = d.call("spin", &num(&[360.0, 1.0])).unwrap();
    assert_eq!(d.heading, 10);
    let Some(Wait::Timeline(t)) = e.wait else {
        panic!("a timeline")
    };
    assert!(t.paced());
    assert_eq!(t.end, Duration::from_secs(1));
    let ms = Duration::from_millis;
    // The first step, at once: 0° turned, and not the last.
    assert_eq!(
        t.spin_step(Duration::ZERO),
        (vec![Driver::drive(10, 0)], false)
    );
    // A round trip of 121 ms later: round(43.56) = 44°.
    assert_eq!(t.spin_step(ms(121)), (vec![Driver::drive(54, 0)], false));
    // Halfway: 180° on.
    assert_eq!(t.spin_step(ms(500)), (vec![Driver::drive(190, 0)], false));
    // 359.5° rounds to 360 (half to even): the last step, a little before the duration.
    assert_eq!(t.spin_step(ms(998)), (vec![Driver::drive(9, 0)], false));
    assert_eq!(
        t.spin_step(Duration::from_micros(998_612)),
        (vec![Driver::drive(10, 0)], true)
    );
    // Late: where it started, the last step.
    assert_eq!(t.spin_step(ms(1_250)), (vec![Driver::drive(10, 0)], true));
    // Counter-clockwise, 90°: at least BOLT's 0.45 s per turn; the heading it ends on is the
    // driver's at once.
    let e = d.call("spin", &num(&[-90.0, 0.0])).unwrap();
    assert_eq!(d.heading, 280);
    let Some(Wait::Timeline(t)) = e.wait else {
        panic!("a timeline")
    };
    assert_eq!(t.end, Duration::from_micros(112_500));
    assert_eq!(t.spin_step(ms(50)), (vec![Driver::drive(330, 0)], false));
    assert_eq!(t.spin_step(ms(200)), (vec![Driver::drive(280, 0)], true));
}

/// Every model, as spherov2's `set_speed` bounds it (`bound_value(-255, speed, 255)`,
/// after Mini's `round((speed ± 126) · 2/3)`): huge and infinite speeds are full speed
/// their way, never the other way round; NaN is refused and changes nothing.
#[test]
fn huge_negative_and_infinite_speeds_clamp_on_every_model_and_nan_is_refused() {
    for model in Model::ALL {
        let mut d = Driver::new(model);
        for (v, want) in [
            (1e19, 255),
            (1e308, 255),
            (f64::INFINITY, 255),
            (-1e19, -255),
            (-1e308, -255),
            (f64::NEG_INFINITY, -255),
            (9.2e18, 255),
            (256.0, 255),
            (-0.0, 0),
        ] {
            d.call("setSpeed", &num(&[v])).unwrap();
            assert_eq!(d.speed, want, "{model:?} setSpeed({v})");
            d.call("roll", &num(&[0.0, v, 0.0])).unwrap();
            assert_eq!(d.speed, want, "{model:?} roll(0, {v}, 0)");
        }
        d.call("setSpeed", &num(&[10.0])).unwrap();
        let before = d.speed;
        let e = d.call("setSpeed", &num(&[f64::NAN])).unwrap_err();
        assert!(e.contains("setSpeed") && e.contains("NaN"), "{e}");
        assert!(d.call("roll", &num(&[0.0, f64::NAN, 1.0])).is_err());
        assert_eq!(d.speed, before, "{model:?}");
    }
    // Mini as spherov2 maps it: 255 is 254, 256 and more 255, 0.3 is 84.
    let mut d = Driver::new(Model::Mini);
    for (v, want) in [(255.0, 254), (256.0, 255), (0.3, 84), (-255.0, -254)] {
        d.call("setSpeed", &num(&[v])).unwrap();
        assert_eq!(d.speed, want, "Mini setSpeed({v})");
    }
}

#[test]
fn durations_past_a_day_or_not_finite_are_refused_naming_the_call_and_change_nothing() {
    let mut d = Driver::new(Model::Bolt);
    for (call, args) in [
        ("roll", vec![90.0, 100.0, 1e12]),
        ("roll", vec![90.0, 100.0, f64::INFINITY]),
        ("spin", vec![1e12, 1.0]),
        ("spin", vec![360.0, 1e12]),
        ("spin", vec![f64::INFINITY, 1.0]),
        ("delay", vec![86_401.0]),
        ("rawMotor", vec![10.0, 10.0, 1e300]),
        ("fade", vec![0.0, 0.0, 0.0, 9.0, 9.0, 9.0, 1e9]),
        ("strobe", vec![255.0, 0.0, 0.0, 0.05, 1e12]),
        ("strobe", vec![255.0, 0.0, 0.0, 10.0, 10_000.0]),
        ("strobe", vec![255.0, 0.0, 0.0, f64::INFINITY, 1.0]),
    ] {
        let e = d.call(call, &num(&args)).unwrap_err();
        assert!(e.starts_with(call), "{call}{args:?}: {e}");
        assert_eq!((d.heading, d.speed, d.main), (0, 0, [0; 3]), "{call}");
    }
    // A day is fine, and negative is none.
    d.call("delay", &num(&[86_400.0])).unwrap();
    let e = d.call("roll", &num(&[0.0, 10.0, -5.0])).unwrap();
    assert_eq!(
        e.wait,
        Some(Wait::Timeline(Timeline {
            steps: Steps::Once(Duration::ZERO, vec![Driver::drive(0, 0)]),
            end: Duration::ZERO
        }))
    );
    // rollDistance's third number is centimetres, not seconds.
    d.call("rollDistance", &num(&[0.0, 10.0, 100_000.0]))
        .unwrap();
}

#[test]
fn a_long_spin_or_strobe_is_a_few_numbers_however_long() {
    let mut d = Driver::new(Model::Bolt);
    let e = d.call("spin", &num(&[360.0 * 1000.0, 1.0])).unwrap();
    let Some(Wait::Timeline(t)) = e.wait else {
        panic!("a timeline")
    };
    // One step at a time as the answers come, none listed up front.
    assert!(t.paced() && std::mem::size_of_val(&t) < 128);
    assert_eq!(t.end, Duration::from_secs(450));
    let e = d
        .call("strobe", &num(&[255.0, 0.0, 0.0, 0.0, 1e6]))
        .unwrap();
    let Some(Wait::Timeline(t)) = e.wait else {
        panic!("a timeline")
    };
    assert_eq!((t.len(), t.end), (2_000_000, Duration::ZERO));
}

#[test]
fn nan_too_many_arguments_and_huge_texts_are_refused_naming_the_call() {
    let mut d = Driver::new(Model::Bolt);
    let e = d
        .call(
            "scrollMatrixText",
            &[Arg::Text("HI".into()), Arg::Num(f64::NAN)],
        )
        .unwrap_err();
    assert!(e.starts_with("scrollMatrixText"), "{e}");
    // Infinity frames a second is the most there is, not a division by zero.
    let mut args = vec![Arg::Text("HI".into())];
    args.extend(num(&[1.0, 2.0, 3.0, f64::INFINITY, 1.0]));
    d.call("scrollMatrixText", &args).unwrap();
    args[4] = Arg::Num(f64::NEG_INFINITY);
    d.call("scrollMatrixText", &args).unwrap();
    let e = d
        .call("speak", &[Arg::Text("x".repeat(MAX_TEXT + 1))])
        .unwrap_err();
    assert!(e.starts_with("speak"), "{e}");
    let e = d
        .call("listenForIRMessage", &num(&vec![1.0; MAX_ARGS + 1]))
        .unwrap_err();
    assert!(e.starts_with("listenForIRMessage"), "{e}");
}

#[test]
fn an_animation_registers_its_frames_then_itself_and_plays_only_once_registered() {
    let mut d = Driver::new(Model::Bolt);
    assert!(d.call("playMatrixAnimation", &num(&[0.0, 1.0])).is_err());
    let mut a = vec![2.0, 0.0, 2.0, 255.0, 0.0, 0.0, 0.0, 0.0, 255.0, 2.0];
    a.extend(std::iter::repeat_n(0.0, 64));
    a.extend(std::iter::repeat_n(1.0, 64));
    let e = d.call("registerMatrixAnimation", &num(&a)).unwrap();
    assert_eq!(e.now.len(), 3);
    assert_eq!(e.now[1], Act::Matrix(Matrix::SaveFrame(1, [[1; 8]; 8])));
    assert_eq!(
        e.now[2],
        Act::Matrix(Matrix::SaveAnimation {
            id: 0,
            fps: 2,
            fade: false,
            palette: vec![[255, 0, 0], [0, 0, 255]],
            frames: vec![0, 1],
        })
    );
    let e = d.call("playMatrixAnimation", &num(&[0.0, 0.0])).unwrap();
    assert_eq!(e.now, vec![Act::Matrix(Matrix::Play(0, false))]);
    // A second animation's frames follow the first's.
    a[9] = 1.0;
    a.truncate(10 + 64);
    let e = d.call("registerMatrixAnimation", &num(&a)).unwrap();
    assert_eq!(e.now[0], Act::Matrix(Matrix::SaveFrame(2, [[0; 8]; 8])));
    // A pixel past the palette, a missing pixel, 17 colours: errors, nothing registered.
    let mut bad = a.clone();
    bad[12] = 2.0;
    assert!(
        d.call("registerMatrixAnimation", &num(&bad))
            .unwrap_err()
            .contains("row 0 column 2")
    );
    let mut bad = a.clone();
    bad.truncate(20);
    assert!(
        d.call("registerMatrixAnimation", &num(&bad))
            .unwrap_err()
            .contains("missing")
    );
    bad[2] = 17.0;
    assert!(d.call("registerMatrixAnimation", &num(&bad)).is_err());
    assert_eq!((d.animations, d.frames), (2, 3));
}

#[test]
fn strobe_starts_dark() {
    let mut d = Driver::new(Model::Bolt);
    let e = d
        .call("strobe", &num(&[255.0, 0.0, 0.0, 0.1, 2.0]))
        .unwrap();
    let Some(Wait::Timeline(t)) = e.wait else {
        panic!("a timeline")
    };
    assert_eq!(t.len(), 4);
    assert_eq!(t.acts(0), vec![Act::Main([0, 0, 0])]);
    assert_eq!(t.acts(1), vec![Act::Main([255, 0, 0])]);
    assert_eq!(t.at(3), Duration::from_millis(300));
    assert_eq!(t.end, Duration::from_millis(400));
    assert_eq!(d.main, [255, 0, 0]);
}

/// Hostile numbers and texts as the natives pass them on.
fn hostile() -> Vec<Arg> {
    let mut v: Vec<Arg> = [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        1e308,
        -1e308,
        -0.0,
        0.0,
        0.5,
        1.0,
        -1.0,
        7.0,
        255.0,
        256.0,
        1e19,
        9.007_199_254_740_993e15,
        f64::MIN_POSITIVE,
        86_401.0,
    ]
    .into_iter()
    .map(Arg::Num)
    .collect();
    v.extend(
        ["", "HI", "A", "\u{e9}", "twolegs"]
            .into_iter()
            .map(|t| Arg::Text(t.into())),
    );
    v.push(Arg::Text("x".repeat(MAX_TEXT + 1)));
    v
}

/// Every call's effect is within bounds, or its error names it (and then changed nothing).
fn call_checked(d: &mut Driver, name: &str, args: &[Arg]) {
    let before = format!("{d:?}");
    match d.call(name, args) {
        Ok(e) => crate::edu::probe::check_effect(name, &e.now, e.wait.as_ref()),
        Err(m) => {
            assert!(m.contains(name), "{name}{args:?}: {m}");
            assert_eq!(format!("{d:?}"), before, "{name}{args:?}: {m}");
        }
    }
}

/// Every call of the table (and `setBackLedBrightness`, as the prelude names it), on every
/// model, with each hostile value in every place.
#[test]
fn every_call_with_each_hostile_value_on_every_model_is_an_effect_in_bounds_or_an_error() {
    let values = hostile();
    for model in Model::ALL {
        let mut d = Driver::new(model);
        let names = crate::edu::calls::CALLS
            .iter()
            .map(|c| c.name)
            .chain(["setBackLedBrightness"]);
        for name in names {
            for v in &values {
                for n in 0..8 {
                    call_checked(&mut d, name, &vec![v.clone(); n]);
                }
            }
        }
    }
}

fn arg() -> impl proptest::strategy::Strategy<Value = Arg> {
    use proptest::prelude::*;
    prop_oneof![
        prop::sample::select(hostile()),
        any::<f64>().prop_map(Arg::Num),
        (-400.0..400.0f64).prop_map(Arg::Num),
        "[ -~]{0,30}".prop_map(Arg::Text),
    ]
}

proptest::proptest! {
    /// Random arguments of any kind, any count, to every call.
    #[test]
    fn any_arguments_to_any_call_are_an_effect_in_bounds_or_an_error_naming_it(
        model in proptest::sample::select(Model::ALL.to_vec()),
        call in proptest::sample::select(crate::edu::calls::CALLS.to_vec()),
        args in proptest::collection::vec(arg(), 0..12),
    ) {
        let mut d = Driver::new(model);
        call_checked(&mut d, call.name, &args);
        call_checked(&mut d, call.name, &args);
    }
}
