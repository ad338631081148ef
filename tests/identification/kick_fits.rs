//! Fitting the kicks' initial states: with no effect parameter free (the
//! base model), the kicks are independent problems.

use crate::common::*;
use bikedyn::generated::ExtendedFree;
use bikedyn::runtime::identify::{
    fit_candidate, Candidate, EffectParameter, IdentifyOptions, Segment, Setup, Weights, NUISANCE,
};
use bikedyn::runtime::linearize::parameter_vector;
use bikedyn::runtime::model::{CoordinateRole as R, MultibodyModel};
use bikedyn::runtime::parameters::ThesisParameters;
use bikedyn::runtime::simulate::{simulate, Inputs, Simulation};

/// The thesis bicycle's parameter vector for model `M` at `speed` (m/s).
fn thesis_parameters<M: MultibodyModel>(speed: f64) -> Vec<f64> {
    let thesis = ThesisParameters::thesis_bicycle();
    parameter_vector::<M>(|s| thesis.get(s), speed).unwrap()
}

/// A measured-style segment of a simulated kick: roll and steer (rad) at
/// every output sample, the speed (m/s) at every `speed_every`-th, as a
/// wheel's magnet gives it sparsely.
fn kick_segment(name: String, sim: &Simulation, roll: Vec<f64>, steer: Vec<f64>, speed_every: usize) -> Segment {
    let speed_t: Vec<f64> = sim.t.iter().step_by(speed_every).copied().collect();
    let speed_v: Vec<f64> = sim.speed.iter().step_by(speed_every).copied().collect();
    Segment::new(name, 0.0, sim.t.clone(), roll, steer, speed_t, speed_v, None).unwrap()
}

/// A candidate of one parameter `symbol` (tied to `tied`), without prior
/// or bounds, started at a tenth of `scale`.
fn one_parameter_candidate(name: &str, symbol: &str, tied: &[&str], scale: f64, speed_decay: bool) -> Candidate {
    Candidate {
        name: name.into(),
        effects: vec![name.into()],
        parameters: vec![EffectParameter {
            symbol: symbol.into(),
            tied: tied.iter().map(|t| t.to_string()).collect(),
            moves: Vec::new(),
            scale,
            dissipative: true,
            unit: String::new(),
            initial: None,
            lower: None,
            upper: None,
            shape: false,
            prior: None,
            gross_beyond: 3.0,
        }],
        fixed: Vec::new(),
        speed_decay,
        reason: String::new(),
        alternative_model: false,
        nonsmooth: false,
    }
}

/// A set's kicks below the weave speed fall within their window, and their
/// fit is slow and far from the data while the others fit to their noise.
/// The base fit must still fit every kick as well as it would alone: a
/// kick's fitted initial state is the same fitted beside a falling kick as
/// on its own (under one damping and one accept-or-reject for all, the
/// falling kick held the others to its short steps, and the fit stopped at
/// its budget unconverged), and each kick's is the state it was simulated
/// from.
#[test]
fn a_falling_kick_does_not_hold_back_the_base_fit_of_the_others() {
    type M = ExtendedFree;
    let (kick, opts) = kick_and_tight_options();
    let param = thesis_parameters::<M>(kick.speed);
    // A kick at 5.5 m/s (the weave decays) and one at 2.5 m/s, three times as
    // hard (below the weave speed: the weave grows and the bicycle falls
    // within the window).
    let kicks = [(5.5, 1.0, 2.0), (2.5, 3.0, 3.0)];
    let mut segments = Vec::new();
    let mut truth = Vec::new();
    for (i, &(speed, size, window)) in kicks.iter().enumerate() {
        let mut ic = kick;
        ic.speed = speed;
        ic.roll_rate *= size;
        ic.steer_rate *= size;
        let sim = simulate::<M>(&param, &ic, &Inputs::default(), window, &opts).unwrap();
        let roll = sim.require_coordinate(R::Roll, "test").unwrap();
        let steer = sim.require_coordinate(R::Steer, "test").unwrap();
        println!("kick {i}: roll {:.3} rad at the window's end", roll.last().unwrap());
        if i == 1 {
            let last = roll.last().unwrap().abs();
            assert!(last > 0.2, "the slow kick falls: roll {last} rad at the window's end");
        }
        segments.push(kick_segment(format!("kick{i}"), &sim, roll, steer, 25));
        truth.push(ic);
    }
    let weights = vec![
        Weights {
            roll: 0.005,
            steer: 0.01,
            speed: 0.05,
        };
        segments.len()
    ];
    // Every fit starts away from the truth: the rates read off the data
    // are moved by a tenth.
    let start = |s: &Segment| -> [f64; NUISANCE] {
        let mut x = s.initial;
        x[2] *= 1.1;
        x[3] *= 0.9;
        x
    };
    let fit = |segs: &[Segment], w: &[Weights]| {
        let setup = Setup::new::<M>(&param, segs, w, &[]).unwrap();
        let x0: Vec<[f64; NUISANCE]> = segs.iter().map(start).collect();
        fit_candidate(&setup, vec![], &[], &x0, &[], &IdentifyOptions::default(), None).unwrap()
    };
    let together = fit(&segments, &weights);
    for (i, seg) in segments.iter().enumerate() {
        let alone = fit(std::slice::from_ref(seg), &weights[i..=i]);
        let (a, b) = (&together.nuisance[i], &alone.nuisance[0]);
        println!("kick {i}: together {a:?}, alone {b:?}");
        assert!(
            a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-12 * (1.0 + y.abs())),
            "kick {i}: fitted beside the other {a:?}, alone {b:?}"
        );
        // The state it was simulated from: roll, steer and their rates, to
        // what the fit's stopping rule resolves (it stops when a step lowers
        // the cost by less than 1e-6 relative: a state within about its
        // square root).
        let ic = &truth[i];
        for (j, (got, want)) in a
            .iter()
            .zip([ic.roll, ic.steer, ic.roll_rate, ic.steer_rate])
            .enumerate()
        {
            assert!(
                (got - want).abs() < 1e-3 * (0.01 + want.abs()),
                "kick {i}, initial state {j}: fitted {got}, simulated from {want}"
            );
        }
    }
}

/// A fit with an effect parameter free must end on the minimum of its
/// profile: the weighted error with every kick's initial state fitted on its
/// own at each value of the parameter. The kicks here are simulated with
/// steer damping and drag, and fitted with rolling resistance alone, so the
/// model misses and the parameter trades against the kicks' starting speeds
/// and angles along a curved valley. There, joint steps of the parameter
/// and every kick's state under one damping were refused and then crawled
/// (on the oracle's steer_damping_small the fit ended 0.3 % above the
/// profile at its own value and 7 % short of the profile's minimum).
#[test]
fn a_fit_of_an_effect_parameter_ends_on_the_minimum_of_its_profile() {
    type M = ExtendedFree;
    let (kick, opts) = kick_and_tight_options();
    let at = |s: &str| M::PARAMETERS.iter().position(|p| *p == s).unwrap();
    let base = thesis_parameters::<M>(kick.speed);
    let mut truth = base.clone();
    truth[at("c_steer")] = 0.3;
    truth[at("CdA")] = 0.4;
    truth[at("rho_air")] = 1.2;
    // Kicks from below the weave speed (the bicycle falls within the
    // window) to well above it.
    let kicks = [
        (3.2, 2.0, 2.5),
        (4.5, 1.0, 3.0),
        (5.5, 1.0, 3.0),
        (6.5, 1.5, 3.0),
        (7.5, 1.0, 3.0),
    ];
    let mut segments = Vec::new();
    for (i, &(speed, size, window)) in kicks.iter().enumerate() {
        let mut ic = kick;
        ic.speed = speed;
        ic.roll_rate *= size;
        ic.steer_rate *= size;
        let sim = simulate::<M>(&truth, &ic, &Inputs::default(), window, &opts).unwrap();
        let roll = sim.require_coordinate(R::Roll, "test").unwrap();
        let steer = sim.require_coordinate(R::Steer, "test").unwrap();
        segments.push(kick_segment(format!("kick{i}"), &sim, roll, steer, 25));
    }
    let weights = vec![
        Weights {
            roll: 0.005,
            steer: 0.01,
            speed: 0.05,
        };
        segments.len()
    ];
    let x0: Vec<[f64; NUISANCE]> = segments.iter().map(|s| s.initial).collect();
    let rolling = one_parameter_candidate("rolling_resistance", "Crr_rear", &["Crr_front"], 0.01, true);
    let opts = IdentifyOptions::default();
    let setup = Setup::new::<M>(&base, &segments, &weights, &[&rolling]).unwrap();
    let fit = fit_candidate(
        &setup,
        vec!["rolling_resistance".into()],
        &[0.001],
        &x0,
        &[],
        &opts,
        None,
    )
    .unwrap();
    let crr = fit.values[0];
    // The profile: the base model with the coefficient held, each kick's
    // initial state fitted on its own.
    let profile = |c: f64| {
        let mut held = base.clone();
        held[at("Crr_rear")] = c;
        held[at("Crr_front")] = c;
        let setup = Setup::new::<M>(&held, &segments, &weights, &[]).unwrap();
        fit_candidate(&setup, vec![], &[], &fit.nuisance, &[], &opts, None)
            .unwrap()
            .chi2
    };
    let (below, here, above) = (profile(0.97 * crr), profile(crr), profile(1.03 * crr));
    println!("Crr {crr}: fit {}, profile {below} / {here} / {above}", fit.chi2);
    assert!(crr > 0.0, "drag is a speed loss: Crr {crr}");
    // The kicks' states are at their own optimum at the fitted value...
    assert!(
        fit.chi2 <= here * (1.0 + 1e-4),
        "fit {} against the profile's {here} at Crr {crr}",
        fit.chi2
    );
    // ...and the value is at the profile's minimum (3 % either side costs more).
    assert!(
        here < below && here < above,
        "Crr {crr}: profile {below} at -3 %, {here}, {above} at +3 %"
    );
}

/// A kick below the weave speed falls within its window, and its fit has
/// more than one minimum: started from a state whose speed is off, the fit
/// can trade the speed for the fall's timing (the oracle's control_a run08,
/// kicked at 3.48 m/s, was fitted at 4.22 m/s, its roll missed by 11 deg
/// RMS). The base fit also starts each kick from its measured speed, held
/// while the other states are fitted, and keeps the better fit: the kick's
/// state comes back from a start 0.8 m/s too fast.
#[test]
fn a_falling_kick_is_fitted_from_its_measured_speed_when_the_start_is_off() {
    type M = ExtendedFree;
    let (kick, opts) = kick_and_tight_options();
    let param = thesis_parameters::<M>(kick.speed);
    let mut ic = kick;
    ic.speed = 2.5;
    ic.roll_rate *= 3.0;
    ic.steer_rate *= 3.0;
    let sim = simulate::<M>(&param, &ic, &Inputs::default(), 3.0, &opts).unwrap();
    let roll = sim.require_coordinate(R::Roll, "test").unwrap();
    let steer = sim.require_coordinate(R::Steer, "test").unwrap();
    assert!(roll.last().unwrap().abs() > 0.2, "the kick falls");
    let seg = kick_segment("fall".into(), &sim, roll, steer, 50);
    let weights = [Weights {
        roll: 0.005,
        steer: 0.01,
        speed: 0.3,
    }];
    let segments = [seg];
    let setup = Setup::new::<M>(&param, &segments, &weights, &[]).unwrap();
    let mut start: [f64; NUISANCE] = segments[0].initial;
    start[4] += 0.8;
    let fit = fit_candidate(&setup, vec![], &[], &[start], &[], &IdentifyOptions::default(), None).unwrap();
    let x = fit.nuisance[0];
    println!("fitted {:?}, chi2 {}", &x[..5], fit.chi2);
    for (j, want) in [ic.roll, ic.steer, ic.roll_rate, ic.steer_rate, ic.speed]
        .into_iter()
        .enumerate()
    {
        assert!(
            (x[j] - want).abs() < 1e-3 * (0.01 + want.abs()),
            "initial state {j}: fitted {}, simulated from {want}",
            x[j]
        );
    }
}
