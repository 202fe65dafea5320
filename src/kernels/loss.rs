//! The paper's closed-loop loss as one backend operation on Flex, with its backward
//! written by hand. In: the terms `[windows, outputs]` the network gives, which of their
//! columns is each axis's scale factor and bias, the DVL velocity and the ground truth.
//! Out: the loss, in (cm/s)²; backward, the terms' gradient.
//!
//! Composed of burn's operations the loss is about a dozen tensors and as many autodiff
//! nodes for a batch of a few thousand values: a tenth of a training step on one thread,
//! all of it serial while a model's other cores wait. Here it is one pass over the batch
//! each way. The loss composed of burn's operations (`train`, on other backends) is the
//! reference that the tests compare this one with.

use super::{f32_tensor, values};
use burn::backend::autodiff::checkpoint::base::Checkpointer;
use burn::backend::autodiff::checkpoint::strategy::NoCheckpointing;
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind};
use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{Autodiff, Flex, TensorMetadata};
use burn::tensor::{Shape, Tensor};
use std::sync::Arc;

/// Which column of the terms corrects each axis (x, y, z): its scale factor in percent and
/// its bias in cm/s, or none where the error model has no such term.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TermColumns {
    pub scale_pct: [Option<usize>; 3],
    pub bias_cm_s: [Option<usize>; 3],
}

/// The mean over the windows' samples of the squared error, summed over the three axes,
/// of the DVL velocity corrected by `terms`, `(dvl − bias) / (1 + scale / 100)`, against
/// the ground truth: `dvl_cm_s` and `truth_cm_s` are `[windows, time, 3]` in cm/s. On an
/// autodiff device, one backward node gives the terms' gradient.
pub fn closed_loop_loss(
    terms: Tensor<2>,
    columns: TermColumns,
    dvl_cm_s: Tensor<3>,
    truth_cm_s: Tensor<3>,
) -> Tensor<1> {
    assert!(
        super::network::runs_on(&terms),
        "closed_loop_loss: f32 tensors on Flex only"
    );
    let [windows, outputs] = terms.dims();
    assert_eq!(
        windows,
        dvl_cm_s.dims()[0],
        "closed_loop_loss: a row of terms a window"
    );
    let read = columns.scale_pct.iter().chain(&columns.bias_cm_s).flatten();
    assert!(
        read.max().is_none_or(|&c| c < outputs),
        "closed_loop_loss: columns {columns:?} beyond {outputs} terms"
    );
    if terms.device().is_autodiff() {
        type Tracked = Autodiff<Flex>;
        let data = |t: Tensor<3>| {
            t.try_into_primitive::<Tracked>()
                .expect("on Autodiff<Flex>")
                .into_primitive()
        };
        let batch = Batch::new(columns, data(dvl_cm_s), data(truth_cm_s));
        let terms = terms
            .try_into_primitive::<Tracked>()
            .expect("on Autodiff<Flex>");
        Tensor::from_primitive::<Tracked>(tracked_loss(terms, batch))
    } else {
        let data = |t: Tensor<3>| t.try_into_primitive::<Flex>().expect("on Flex");
        let batch = Batch::new(columns, data(dvl_cm_s), data(truth_cm_s));
        let terms = terms.try_into_primitive::<Flex>().expect("on Flex");
        Tensor::from_primitive::<Flex>(scalar(batch.loss(values(&terms.to_contiguous()))))
    }
}

/// The loss under autodiff, with one backward node whose parent is `terms`.
fn tracked_loss(terms: FloatTensor<Autodiff<Flex>>, batch: Batch) -> FloatTensor<Autodiff<Flex>> {
    let node = terms.node();
    let terms = terms.into_primitive().to_contiguous();
    let loss = scalar(batch.loss(values(&terms)));
    match LossStep
        .prepare::<NoCheckpointing>([node])
        .compute_bound()
        .stateful()
    {
        OpsKind::Tracked(prep) => prep.finish(
            LossState {
                batch: Arc::new(batch),
                terms,
            },
            loss,
        ),
        OpsKind::UnTracked(prep) => prep.finish(loss),
    }
}

/// The one backward node: its parent is the terms.
#[derive(Debug)]
struct LossStep;

/// What the backward reads: the batch and the terms it was corrected with.
#[derive(Debug, Clone)]
struct LossState {
    batch: Arc<Batch>,
    terms: FlexTensor,
}

impl Backward<Flex, 1> for LossStep {
    type State = LossState;

    fn backward(
        self,
        ops: Ops<Self::State, 1>,
        grads: &mut Gradients,
        _checkpointer: &mut Checkpointer,
    ) {
        let grad = grads.consume::<Flex>(&ops.node).to_contiguous();
        let upstream = values(&grad)[0];
        let [parent] = ops.parents;
        if let Some(node) = parent {
            let terms = &ops.state.terms;
            let gradient = ops.state.batch.gradient(values(terms), upstream);
            grads.register::<Flex>(node.id, f32_tensor(gradient, terms.shape()));
        }
    }
}

/// One batch's velocities, contiguous, and the columns its terms are read at.
#[derive(Debug)]
struct Batch {
    columns: TermColumns,
    dvl: FlexTensor,
    truth: FlexTensor,
    windows: usize,
    time: usize,
}

impl Batch {
    fn new(columns: TermColumns, dvl: FlexTensor, truth: FlexTensor) -> Self {
        let (dvl, truth) = (dvl.to_contiguous(), truth.to_contiguous());
        let shape = dvl.shape();
        assert_eq!(
            shape,
            truth.shape(),
            "closed_loop_loss: DVL and truth shapes"
        );
        assert_eq!(shape[2], 3, "closed_loop_loss: three axes");
        Self {
            columns,
            windows: shape[0],
            time: shape[1],
            dvl,
            truth,
        }
    }

    /// A window's factor (1 + scale / 100) and bias on each axis, from its row of terms.
    fn correction(&self, row: &[f32]) -> ([f32; 3], [f32; 3]) {
        let term = |column: Option<usize>| column.map_or(0.0, |c| row[c]);
        let TermColumns {
            scale_pct,
            bias_cm_s,
        } = self.columns;
        (
            scale_pct.map(|c| term(c) / 100.0 + 1.0),
            bias_cm_s.map(term),
        )
    }

    /// The samples of window `w` as (DVL, truth) rows of three axes.
    fn samples(&self, w: usize) -> impl Iterator<Item = (&[f32], &[f32])> {
        let span = w * self.time * 3..(w + 1) * self.time * 3;
        let dvl = values(&self.dvl)[span.clone()].chunks_exact(3);
        dvl.zip(values(&self.truth)[span].chunks_exact(3))
    }

    fn loss(&self, terms: &[f32]) -> f32 {
        let outputs = terms.len() / self.windows.max(1);
        let mut sum = 0.0f64;
        for w in 0..self.windows {
            let (factor, bias) = self.correction(&terms[w * outputs..][..outputs]);
            for (dvl, truth) in self.samples(w) {
                for a in 0..3 {
                    let error = (dvl[a] - bias[a]) / factor[a] - truth[a];
                    sum += f64::from(error * error);
                }
            }
        }
        (sum / (self.windows * self.time) as f64) as f32
    }

    /// The gradient of `upstream` × the loss with respect to `terms`, `[windows, outputs]`.
    fn gradient(&self, terms: &[f32], upstream: f32) -> Vec<f32> {
        let outputs = terms.len() / self.windows.max(1);
        let mut gradient = vec![0.0f32; terms.len()];
        let per_value = 2.0 * upstream / (self.windows * self.time) as f32;
        for w in 0..self.windows {
            let (factor, bias) = self.correction(&terms[w * outputs..][..outputs]);
            // d loss / d (dvl − bias) and d loss / d factor, summed over the window's samples.
            let (mut by_offset, mut by_factor) = ([0.0f32; 3], [0.0f32; 3]);
            for (dvl, truth) in self.samples(w) {
                for a in 0..3 {
                    let corrected = (dvl[a] - bias[a]) / factor[a];
                    let error = (corrected - truth[a]) * per_value;
                    by_offset[a] += error / factor[a];
                    by_factor[a] -= error * corrected / factor[a];
                }
            }
            let row = &mut gradient[w * outputs..][..outputs];
            for a in 0..3 {
                if let Some(c) = self.columns.scale_pct[a] {
                    row[c] += by_factor[a] / 100.0;
                }
                if let Some(c) = self.columns.bias_cm_s[a] {
                    row[c] -= by_offset[a];
                }
            }
        }
        gradient
    }
}

/// The loss as a one-value tensor, as burn's `sum` gives it.
fn scalar(loss: f32) -> FlexTensor {
    f32_tensor(vec![loss], Shape::new([1]))
}
