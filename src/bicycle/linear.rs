//! The linear equations of a bicycle: the canonical matrices where they
//! exist, otherwise the chosen model linearized at each speed; and the
//! zero-wheel-radius limit.

use super::{default_model_of, Bicycle, BicycleError};
use crate::registry::BuiltIn;
use bikedyn_runtime::canonical::CanonicalMatrices;
use bikedyn_runtime::eigen::LinearBicycle;
use bikedyn_runtime::feedback::WithFeedback;
use bikedyn_runtime::linearize::{canonical_matrices, LinearModel, LinearizeError};
use bikedyn_runtime::parameters::{ParameterSet, ThesisParameters};
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry, ModelVisitor};
use bikedyn_runtime::MultibodyModel;
use std::collections::BTreeMap;
use std::marker::PhantomData;

impl<R: ModelRegistry> Bicycle<R> {
    /// Canonical matrices through a chosen model (`None`: the default model).
    pub fn canonical_with(&self, model: Option<&str>) -> Result<CanonicalMatrices, BicycleError> {
        if self.feedback.is_some() {
            return Err(BicycleError::NotCanonical {
                effects: "the [feedback] controller of the file".into(),
            });
        }
        self.plant_canonical_with(model)
    }

    /// [`Bicycle::canonical_with`] of the bicycle without its feedback.
    fn plant_canonical_with(&self, model: Option<&str>) -> Result<CanonicalMatrices, BicycleError> {
        if model.is_none() && self.effects.is_empty() {
            let t = self.thesis()?;
            if let Some(info) = default_model_of::<R>(&t) {
                if t.rear_wheel_radius != 0.0 && t.front_wheel_radius != 0.0 {
                    return R::with_model(info.name, Canonical(&|s: &str| t.get(s)))
                        .expect("registered model")
                        .map_err(|source| BicycleError::Linearize {
                            bike: self.name.clone(),
                            source,
                        });
                }
            }
        }
        let nonzero = self.nonzero_parameters()?;
        let info = self.model_for(model, &nonzero)?;
        self.plant_canonical_of(info, &nonzero)
    }

    /// [`Bicycle::plant_canonical_with`] past its choice of the model
    /// `info` for the bicycle's non-zero parameters `nonzero` (the linear
    /// equations have made that choice already: a stability map's design
    /// made it twice, a twentieth of the browser's map, 2026-12-02).
    fn plant_canonical_of(
        &self,
        info: &'static ModelInfo,
        nonzero: &[(&'static str, f64)],
    ) -> Result<CanonicalMatrices, BicycleError> {
        let active: Vec<String> = nonzero
            .iter()
            .filter(|(s, _)| info.parameter(s).is_some_and(|p| p.effect.is_some()))
            .map(|(s, v)| format!("{s} = {v}"))
            .collect();
        if !active.is_empty() {
            return Err(BicycleError::NotCanonical {
                effects: active.join(", "),
            });
        }
        let t = self.thesis()?;
        if t.rear_wheel_radius == 0.0 || t.front_wheel_radius == 0.0 {
            // No effect is active here, so the matrices are the Whipple
            // bicycle's, which the built-in models give for any registry.
            return canonical_zero_radius(&t);
        }
        // `Bicycle::lookup`, with the thesis parameters converted above.
        let lookup = |s: &str| t.get(s).or_else(|| self.effects.get(s).copied());
        R::with_model(info.name, Canonical(&lookup))
            .expect("registered model")
            .map_err(|source| BicycleError::Linearize {
                bike: self.name.clone(),
                source,
            })
    }

    /// The linear roll-steer equations of this bicycle at every speed,
    /// through model `model` (`None`: the default model, [`Bicycle::model`]):
    /// the canonical matrices when the equations have that form (no effect
    /// active), otherwise the model linearized at each speed (damping,
    /// controllers, drag: any effect).
    pub fn linear_with(&self, model: Option<&str>) -> Result<Linear, BicycleError> {
        let open = self.open_loop_with(model)?;
        let Some(schedule) = self.feedback.clone() else {
            return Ok(open);
        };
        let info = self.model(model)?;
        let added = info.added_coordinates();
        if !info.states.is_empty() || !added.is_empty() {
            return Err(BicycleError::FeedbackOnStates {
                bike: self.name.clone(),
                model: info.name.to_string(),
                states: info.states.iter().chain(&added).copied().collect::<Vec<_>>().join(", "),
            });
        }
        Ok(Linear {
            model: open.model,
            canonical: None,
            equations: Box::new(WithFeedback {
                bicycle: open.equations,
                schedule,
            }),
        })
    }

    /// The equations without the file's feedback (the plant).
    fn open_loop_with(&self, model: Option<&str>) -> Result<Linear, BicycleError> {
        let nonzero = self.nonzero_parameters()?;
        let info = self.model_for(model, &nonzero)?;
        // A model with extra states or coordinates (tyre forces, a rider's
        // lean) has no canonical form (nor roll-steer M, C, K).
        let added = info.added_coordinates();
        let canonical = if info.states.is_empty() && added.is_empty() {
            if model.is_none() && self.effects.is_empty() {
                self.plant_canonical_with(model)
            } else {
                // What `plant_canonical_with` would choose again.
                self.plant_canonical_of(info, &nonzero)
            }
        } else {
            Err(BicycleError::NotCanonical {
                effects: info.states.iter().chain(&added).copied().collect::<Vec<_>>().join(", "),
            })
        };
        match canonical {
            Ok(c) => {
                return Ok(Linear {
                    model: info.name,
                    canonical: Some(c),
                    equations: Box::new(c),
                })
            }
            Err(BicycleError::NotCanonical { .. }) => {}
            Err(e) => return Err(e),
        }
        let lookup = self.lookup()?;
        let equations = R::with_model(info.name, MakeLinear(&lookup))
            .expect("registered model")
            .map_err(|source| BicycleError::Linearize {
                bike: self.name.clone(),
                source,
            })?;
        Ok(Linear {
            model: info.name,
            canonical: None,
            equations,
        })
    }

    /// Canonical matrices from the generated multibody equations, through
    /// the default model.
    pub fn canonical(&self) -> Result<CanonicalMatrices, BicycleError> {
        self.canonical_with(None)
    }
}

/// The linear roll-steer equations of a bicycle through the model chosen.
pub struct Linear {
    /// The generated model they come from.
    pub model: &'static str,
    /// The canonical matrices, when the equations have that form.
    pub canonical: Option<CanonicalMatrices>,
    /// The equations at every speed.
    pub equations: Box<dyn LinearBicycle + Send>,
}

impl LinearBicycle for Linear {
    fn at_speed(&self, v: f64) -> Result<bikedyn_runtime::eigen::SpeedMatrices, bikedyn_runtime::eigen::EigenError> {
        self.equations.at_speed(v)
    }
    fn canonical(&self) -> Option<&CanonicalMatrices> {
        self.canonical.as_ref()
    }
    fn first_order(&self) -> Option<&dyn bikedyn_runtime::eigen::StateSpaceBicycle> {
        self.equations.first_order()
    }
}

struct MakeLinear<'a, F: Fn(&str) -> Option<f64>>(&'a F);
impl<F: Fn(&str) -> Option<f64>> ModelVisitor for MakeLinear<'_, F> {
    type Output = Result<Box<dyn LinearBicycle + Send>, LinearizeError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        Ok(Box::new(LinearModel::<M>::new(self.0)?))
    }
}

struct Canonical<'a, F: Fn(&str) -> Option<f64>>(&'a F);
impl<F: Fn(&str) -> Option<f64>> ModelVisitor for Canonical<'_, F> {
    type Output = Result<CanonicalMatrices, LinearizeError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        canonical_matrices::<M>(self.0)
    }
}

/// Canonical matrices of thesis-form parameters, through the model that fits
/// them (the thesis model when the fork mass centre is on the steer axis,
/// the offset variant otherwise; chosen from the registry by parameters).
///
/// A wheel of zero radius (a skate, as in the two-mass-skate bicycle of
/// Kooijman et al. 2011) has its contact point at the wheel centre. The
/// generated model cannot represent it directly (its driving constraint
/// divides by the rear radius and the rim angle of the front contact is then
/// undetermined), so the zero-radius bicycle is reached as a limit: with the
/// wheel's spin inertia zero, the canonical matrices are polynomials of
/// degree 2 in the wheel radii at fixed benchmark geometry (Meijaard et al.
/// 2007, eqs. A 1 - A 27: the radii enter through `mT zT`, `ITxx`, `ITxz`,
/// `zA`, `IAxx`, `IAxz`, `uA`, none above the second power). They are
/// evaluated at radius `h, 2h, 3h` and extrapolated exactly to 0; a fourth
/// radius `4h` checks that the third difference vanishes.
pub fn canonical_of(p: &ThesisParameters) -> Result<CanonicalMatrices, BicycleError> {
    // The default model directly (what `Bicycle::canonical_with` does first),
    // without building a `Bicycle`: this runs once per design in a sweep.
    if p.rear_wheel_radius != 0.0 && p.front_wheel_radius != 0.0 {
        if let Some(info) = default_model_of::<BuiltIn>(p) {
            return crate::generated::with_model(info.name, Canonical(&|s: &str| p.get(s)))
                .expect("registered model")
                .map_err(|source| BicycleError::Linearize {
                    bike: "parameters".into(),
                    source,
                });
        }
    }
    Bicycle::<BuiltIn> {
        name: "parameters".into(),
        parameters: ParameterSet::Thesis(*p),
        warnings: Vec::new(),
        effects: BTreeMap::new(),
        uncertainties: BTreeMap::new(),
        feedback: None,
        registry: PhantomData,
    }
    .canonical()
}

/// Canonical matrices of a bicycle with one or both wheel radii zero (see
/// [`canonical_of`]).
fn canonical_zero_radius(p: &ThesisParameters) -> Result<CanonicalMatrices, BicycleError> {
    let lin = |source| BicycleError::Linearize {
        bike: "zero-radius bicycle".into(),
        source,
    };
    use bikedyn_runtime::parameters::body;
    for (radius, inertia, wheel, radius_symbol, inertia_symbol) in [
        (
            p.rear_wheel_radius,
            p.rear_wheel_i_axial,
            body::REAR_WHEEL,
            "Rt (rR)",
            "I2y (IRyy)",
        ),
        (
            p.front_wheel_radius,
            p.front_wheel_i_axial,
            body::FRONT_WHEEL,
            "Rd (rF)",
            "I5y (IFyy)",
        ),
    ] {
        if radius == 0.0 && inertia != 0.0 {
            return Err(lin(LinearizeError::SkateWithSpinInertia {
                wheel,
                radius_symbol,
                inertia_symbol,
                inertia,
            }));
        }
    }
    let bench = p.to_benchmark()?;
    // Step: a tenth of the wheelbase keeps every sample a plain bicycle.
    let h = 0.1 * bench.wheelbase;
    let at = |s: f64| -> Result<CanonicalMatrices, BicycleError> {
        let mut b = bench;
        if p.rear_wheel_radius == 0.0 {
            b.rear_wheel_radius = s;
        }
        if p.front_wheel_radius == 0.0 {
            b.front_wheel_radius = s;
        }
        canonical_of(&b.to_thesis()?)
    };
    let f = [at(h)?, at(2.0 * h)?, at(3.0 * h)?, at(4.0 * h)?];
    let combine = |w: [f64; 4], get: &dyn Fn(&CanonicalMatrices) -> f64| -> f64 {
        w.iter().zip(&f).map(|(wi, fi)| wi * get(fi)).sum()
    };
    type Entry = fn(&CanonicalMatrices) -> nalgebra::Matrix2<f64>;
    let entries: [Entry; 4] = [|c| c.m0, |c| c.c1, |c| c.k0, |c| c.k2];
    let mut out = [nalgebra::Matrix2::zeros(); 4];
    for (m, get) in entries.iter().enumerate() {
        // Rounding is relative to the matrix, not to an entry that may be
        // structurally zero.
        let scale = f.iter().fold(0.0f64, |a, c| a.max(get(c).amax()));
        for i in 0..2 {
            for j in 0..2 {
                let e = |c: &CanonicalMatrices| get(c)[(i, j)];
                // Third difference: zero for a quadratic, up to rounding.
                let departure = combine([-1.0, 3.0, -3.0, 1.0], &e).abs();
                if departure.is_nan() || departure > 1e-9 * scale {
                    return Err(lin(LinearizeError::ZeroRadiusLimit { departure, scale }));
                }
                // Lagrange extrapolation of a quadratic to radius 0.
                out[m][(i, j)] = combine([3.0, -3.0, 1.0, 0.0], &e);
            }
        }
    }
    Ok(CanonicalMatrices {
        m0: out[0],
        c1: out[1],
        k0: out[2],
        k2: out[3],
        g: bench.g,
    })
}
