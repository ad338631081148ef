//! The nonlinear fits of an identification, run inside the identification
//! model's type (a [`ModelVisitor`]): the stepwise selection, and the
//! simulated channels of every segment before and after for the plots.

use super::IdentifyError;
use crate::bicycle::Bicycle;
use bikedyn_runtime::identify::{
    identify, Candidate, Factory, Identification, IdentifyOptions as FitSettings, ModelFactory, Segment, Setup,
};
use bikedyn_runtime::linearize::parameter_vector;
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry, ModelVisitor};
use bikedyn_runtime::MultibodyModel;

/// Simulated channels of every segment before and after (plots, bias,
/// amplitude of the steer rate), and the typical segment.
pub(super) struct RunPlot {
    pub(super) segment: usize,
    pub(super) before: Vec<Option<bikedyn_runtime::identify::Sim>>,
    pub(super) after: Vec<Option<bikedyn_runtime::identify::Sim>>,
}

pub(super) struct Identify<'a, R: ModelRegistry> {
    pub(super) bike: &'a Bicycle<R>,
    pub(super) alt: Option<&'static ModelInfo>,
    pub(super) segments: &'a [Segment],
    pub(super) candidates: &'a [Candidate],
    pub(super) opts: &'a FitSettings,
    pub(super) progress: &'a (dyn Fn(&str, Option<(usize, usize)>) + Sync),
}

impl<R: ModelRegistry> ModelVisitor for Identify<'_, R> {
    type Output = Result<(Identification, Option<RunPlot>), IdentifyError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        let lookup = self.bike.lookup()?;
        let base = parameter_vector::<M>(&lookup, 5.0)?;
        let alt: Option<Box<dyn ModelFactory>> = match self.alt {
            Some(a) => Some(R::with_model(a.name, MakeFactory { lookup: &lookup }).expect("registered model")?),
            None => None,
        };
        let id = identify::<M>(
            &base,
            self.segments,
            self.candidates,
            alt.as_deref(),
            self.opts,
            self.progress,
        )?;
        // The typical run: median roll error before.
        let mut order: Vec<usize> = (0..self.segments.len()).collect();
        order.sort_by(|&a, &b| id.before.errors[a].roll_rms.total_cmp(&id.before.errors[b].roll_rms));
        let sel: Vec<&Candidate> = id
            .selected
            .iter()
            .filter_map(|n| self.candidates.iter().find(|c| &c.name == n))
            .collect();
        let before = Setup::new::<M>(&base, self.segments, &id.weights, &[])?;
        let after = match alt.as_deref().filter(|_| sel.iter().any(|c| c.alternative_model)) {
            Some(f) => f.setup(self.segments, &id.weights, &sel)?,
            None => Setup::new::<M>(&base, self.segments, &id.weights, &sel)?,
        };
        let plot = order.get(order.len() / 2).map(|&s| RunPlot {
            segment: s,
            before: (0..self.segments.len())
                .map(|i| before.simulated(&[], &self.segments[i], &id.before.nuisance[i]).ok())
                .collect(),
            after: (0..self.segments.len())
                .map(|i| {
                    after
                        .simulated(&id.after.values, &self.segments[i], &id.after.nuisance[i])
                        .ok()
                })
                .collect(),
        });
        Ok((id, plot))
    }
}

struct MakeFactory<'a, F: Fn(&str) -> Option<f64>> {
    lookup: &'a F,
}

impl<F: Fn(&str) -> Option<f64>> ModelVisitor for MakeFactory<'_, F> {
    type Output = Result<Box<dyn ModelFactory>, IdentifyError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        Ok(Box::new(Factory::<M>::new(parameter_vector::<M>(self.lookup, 5.0)?)))
    }
}
