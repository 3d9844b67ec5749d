//! The storage macros against what each type needs on this target, and the basic contract from
//! Rust (the C-side tests are `capi/tests/host_test.c` and the example firmware, run by
//! `cargo xtask test-all`).

use super::*;
use std::boxed::Box;
use std::ptr;

#[test]
fn every_storage_macro_fits_its_type_with_little_slack() {
    let used = used_sizes();
    let macros = [
        GOUGH_PARAMS_SIZE,
        GOUGH_WHEEL_SIZE,
        GOUGH_ESTIMATOR_SIZE,
        GOUGH_RX_SIZE,
        GOUGH_PREVIEW_SIZE,
        GOUGH_VERIFIER_SIZE,
    ];
    let names = ["params", "wheel", "estimator", "rx", "preview", "verifier"];
    for ((u, m), n) in used.iter().zip(macros).zip(names) {
        println!(
            "{n}: needs {u} bytes on this target, GOUGH_{}_SIZE = {m}",
            n.to_uppercase()
        );
        assert!(*u <= m, "{n}: {u} > {m}");
        // The macros are the largest target's need (x86-64) rounded up: keep them tight.
        if cfg!(target_pointer_width = "64") {
            assert!(
                m - u < 64,
                "{n}: {m} bytes declared for {u} needed: shrink the macro"
            );
        }
    }
}

#[test]
fn null_pointers_and_uninitialised_storage_are_errors() {
    let text = include_str!("../../host-tests/data/tyres/MagicFormula61_Parameters.tir");
    let mut p = Box::new(gough_params_t_zeroed());
    let mut line = 7u32;
    // SAFETY: valid pointers or null, as the C API allows.
    unsafe {
        assert_eq!(
            gough_tir_parse(ptr::null(), 3, &mut *p, &mut line),
            GOUGH_E_NULL
        );
        let input = gough_mf_input_t {
            fz: 4000.0,
            vx: 10.0,
            alpha: 0.02,
            ..Default::default()
        };
        let mut out = gough_mf_output_t::default();
        assert_eq!(gough_mf_eval(&*p, &input, 111, &mut out), GOUGH_E_UNINIT);
        assert_eq!(
            gough_tir_parse(text.as_ptr().cast(), text.len(), &mut *p, &mut line),
            GOUGH_OK
        );
        assert_eq!(line, 0);
        assert_eq!(gough_mf_eval(&*p, &input, 111, &mut out), GOUGH_OK);
        assert!(
            out.fy < 0.0,
            "ISO-W: positive α gives negative Fy ({})",
            out.fy
        );
        assert_eq!(
            gough_mf_eval(&*p, &input, 111, ptr::null_mut()),
            GOUGH_E_NULL
        );
        assert_eq!(gough_mf_eval(&*p, &input, 131, &mut out), GOUGH_E_ARG);
        let bad = "[MODEL]\nFITTYP = 61\nLONGVL = x\n";
        assert_eq!(
            gough_tir_parse(bad.as_ptr().cast(), bad.len(), &mut *p, &mut line),
            GOUGH_E_PARSE
        );
        assert_eq!(line, 3);
        // A failed parse leaves the storage unusable.
        assert_eq!(gough_mf_eval(&*p, &input, 111, &mut out), GOUGH_E_UNINIT);
    }
}

#[test]
fn a_preview_through_the_c_api_is_the_core_preview() {
    let text = include_str!("../../host-tests/data/tyres/MagicFormula61_Parameters.tir");
    let mut p = Box::new(gough_params_t_zeroed());
    let mut line = 0u32;
    // Storages as C declares them (zeroed: unmarked).
    // SAFETY: opaque arrays of u64: all-zero bits are valid unmarked storages.
    let mut ests: Vec<gough_estimator_t> = (0..2).map(|_| unsafe { std::mem::zeroed() }).collect();
    // SAFETY: as above.
    let mut pv: Box<gough_preview_t> = Box::new(unsafe { std::mem::zeroed() });
    // SAFETY: valid pointers or null, as the C API allows.
    unsafe {
        assert_eq!(
            gough_tir_parse(text.as_ptr().cast(), text.len(), &mut *p, &mut line),
            GOUGH_OK
        );
        assert_eq!(gough_preview_init(&mut *pv, 0.0), GOUGH_E_ARG);
        assert_eq!(gough_preview_init(ptr::null_mut(), 2.9), GOUGH_E_NULL);
        assert_eq!(gough_preview_front(&mut *pv, &ests[0]), GOUGH_E_UNINIT);
        assert_eq!(gough_preview_init(&mut *pv, 2.9), GOUGH_OK);
        for e in ests.iter_mut() {
            assert_eq!(gough_estimator_init(e, &*p), GOUGH_OK);
        }
    }
    let p32 = core_gough::tir::parse(text).unwrap().params.cast::<f32>();
    let mut ice = p32.clone();
    ice.lmux *= 0.3;
    ice.lmuy *= 0.3;
    let cfg = mu::Config::default();
    let mut banks = [
        Bank::new::<Fast>(&p32, None, cfg).unwrap(),
        Bank::new::<Fast>(&p32, None, cfg).unwrap(),
    ];
    let mut rpv = Preview::new(core_gough::mu::preview::Config::with_wheelbase(2.9f32)).unwrap();
    let mut alone = Bank::new::<Fast>(&p32, None, cfg).unwrap();
    let mut differs = 0;
    for i in 0..3000u32 {
        for w in 0..2 {
            // Front (0) at α −0.05 onto ice at 1.5 s, rear (1) at −0.01, 145 ms later.
            let on_ice = i >= 1500 + if w == 1 { 145 } else { 0 };
            let a = if w == 1 { -0.01 } else { -0.05 } * (i as f32 / 500.0).min(1.0);
            let input = Input {
                fz: 5000.0,
                alpha: a,
                vx: 20.0,
                ..Input::default()
            };
            let q = if on_ice { &ice } else { &p32 };
            let o = mf::eval::<f32, Fast>(q, &input, &Options::default()).unwrap();
            let cs = gough_sample_t {
                t_us: 1000 * i,
                fz: 5000.0,
                fy: o.fy,
                mz: o.mz,
                fx: o.fx,
                vx: 20.0,
                present: GOUGH_HAS_FX | GOUGH_HAS_VX,
                ..Default::default()
            };
            let s = sample(&cs).unwrap();
            let mut ce = gough_estimate_t::default();
            // SAFETY: initialised storages, valid pointers.
            unsafe {
                if w == 1 {
                    assert_eq!(gough_preview_rear(&mut *pv, &mut ests[1], &cs), GOUGH_OK);
                }
                assert_eq!(gough_estimator_update(&mut ests[w], &cs, &mut ce), GOUGH_OK);
                if w == 0 {
                    assert_eq!(gough_preview_front(&mut *pv, &ests[0]), GOUGH_OK);
                }
            }
            if w == 1 {
                rpv.rear::<Fast>(&mut banks[1], &s);
            }
            let r = banks[w].update::<Fast>(&p32, &s);
            if w == 0 {
                rpv.front(&banks[0]);
            } else {
                let a = alone.update::<Fast>(&p32, &s);
                differs += usize::from(a.mu.to_bits() != r.mu.to_bits());
            }
            assert_eq!(
                (ce.mu.to_bits(), ce.sigma.to_bits(), ce.mu_min.to_bits()),
                (r.mu.to_bits(), r.sigma.to_bits(), r.mu_min.to_bits()),
                "wheel {w}, sample {i}"
            );
        }
    }
    assert!(
        rpv.handed() >= 1 && differs > 0,
        "{} {differs}",
        rpv.handed()
    );
}

fn gough_params_t_zeroed() -> gough_params_t {
    // SAFETY: an opaque array of u64: all-zero bits are a valid (unmarked) storage.
    unsafe { std::mem::zeroed() }
}

#[test]
fn a_secured_message_from_c_is_accepted_by_the_device_check_once() {
    let key = [0x7eu8; 16];
    let mut signer = gough_signer_t {
        key,
        mac_len: 8,
        epoch: 4,
        counter: 10,
        all: 0,
    };
    let mut msg = ZERO_MSG;
    msg.kind = GOUGH_MSG_SETTINGS;
    msg.settings.limits = 1;
    msg.settings.fallback_mu = 0.3;
    msg.settings.wheelbase = 2.9;
    let mut v = proto::Verifier::new(proto::Key::new(key), proto::MacLen::DEFAULT, 4);
    v.set_counter(10);
    let mut frames = [gough_frame_t {
        id: 0,
        len: 0,
        data: [0; 8],
    }; GOUGH_MAX_FRAMES];
    let mut sent = Vec::new();
    for round in 0..2 {
        let mut n = 0usize;
        // SAFETY: valid pointers, GOUGH_MAX_FRAMES frames.
        let r = unsafe {
            gough_msg_encode_secured(
                &mut signer,
                &msg,
                round,
                frames.as_mut_ptr(),
                GOUGH_MAX_FRAMES,
                &mut n,
            )
        };
        assert_eq!(r, GOUGH_OK);
        assert_eq!((signer.epoch, signer.counter), (4, 11 + u32::from(round)));
        let mut rx = Reassembler::<MSG_BUF>::new();
        let mut bytes = Vec::new();
        for f in &frames[..n] {
            assert_eq!(f.id, 0x301);
            if let Feed::Done(_) = rx.feed(&f.data[..f.len as usize], 0) {
                bytes = rx.last().to_vec();
            }
        }
        assert!(matches!(v.open(0x301, &bytes), Ok(Msg::Settings(s)) if s.wheelbase == 2.9));
        sent.push(bytes);
    }
    // Replayed: stale. A measurement goes unsecured; a MAC length of 9 is refused.
    assert_eq!(
        v.open(0x301, &sent[0]).unwrap_err().unwrap().code,
        proto::AckCode::StaleFreshness
    );
    let mut n = 0usize;
    signer.mac_len = 9;
    // SAFETY: valid pointers.
    let r = unsafe {
        gough_msg_encode_secured(
            &mut signer,
            &msg,
            0,
            frames.as_mut_ptr(),
            GOUGH_MAX_FRAMES,
            &mut n,
        )
    };
    assert_eq!((r, signer.counter), (GOUGH_E_ARG, 12));
    // SAFETY: null signer.
    let r = unsafe {
        gough_msg_encode_secured(
            ptr::null_mut(),
            &msg,
            0,
            frames.as_mut_ptr(),
            GOUGH_MAX_FRAMES,
            &mut n,
        )
    };
    assert_eq!(r, GOUGH_E_NULL);
}
