//! The worker's seam to the identification core: the [`Identifier`] trait (the daemon's
//! `CoreIdentifier` implements it on the core's workspace) and why a window gave no model.

use super::live::ResponseLine;
use super::window::WindowView;
use propid_numerics::stabilization::Stabilization;
use propid_numerics::{IdentError, ModelReport};

/// Identifies one window: the worker's seam to the identification core.
///
/// Two calls, so that the hot one can be allocation-free: [`Identifier::identify`] inside the
/// window's callback (the window's buffers are borrowed), then [`Identifier::report`] for the
/// published model, after the window has moved on.
pub trait Identifier: Send {
    /// The hot call: identifies the window; must not allocate on success.
    fn identify(&mut self, view: &WindowView<'_>) -> Result<(), IdentifyError>;
    /// The model of the last successful [`Identifier::identify`] (allocates).
    fn report(&self) -> Result<ModelReport, IdentifyError>;
    /// For the web page (allocates; with `--http` only), inside the window's callback: the
    /// window's measured pulse responses with the model's.
    fn response(&mut self, _v: &WindowView<'_>) -> Option<ResponseLine> {
        None
    }
    /// For the web page, after the model line is published (the workspace still holds the
    /// last identification): its stabilization diagram.
    fn stabilization(&mut self) -> Option<Stabilization> {
        None
    }
    /// Isolated outlier samples of the output left out of the last identified window (they
    /// are also in its model's `missing_samples`).
    fn outliers(&self) -> usize {
        0
    }
}

/// Why a complete window gave no model (published as an `identification_failed` warning whose
/// `message` is this error's text).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IdentifyError {
    /// The identification core refused the window.
    #[error(transparent)]
    Core(#[from] IdentError),
    /// [`Identifier::report`] without a successful identification before it.
    #[error("no model identified")]
    NoModel,
}
