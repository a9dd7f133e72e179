//! A compared method: a name and the render settings it runs with for a (scene, regime, seed).

use std::fmt;
use std::sync::atomic::AtomicBool;

use render::session::{render, NoProgress, RenderOutput, RenderSettings};
use render::{RenderError, Scene};

use crate::record::RunRecord;
use crate::regime::Regime;

/// Where one render of a method happens: what a [`Method`]'s settings may depend on.
#[derive(Clone, Copy, Debug)]
pub struct RunContext<'a> {
    /// The scene's name.
    pub scene: &'a str,
    /// The budget of this render (a fraction of the experiment's for error-vs-time samples).
    pub regime: Regime,
    /// The seed.
    pub seed: u64,
    /// Image side in pixels.
    pub size: u32,
    /// Render threads.
    pub threads: usize,
    /// The runs of the methods listed before this one on the same scene and seed (the same
    /// "slot" of the interleaving), e.g. a baseline's mutation count to size a budget by.
    pub previous: &'a [RunRecord],
}

/// Yields the settings template of a render.
type SettingsFn = dyn Fn(&RunContext<'_>) -> RenderSettings + Send + Sync;
/// Renders a scene with resolved settings.
type RenderFn = dyn Fn(&Scene, &RenderSettings) -> Result<RenderOutput, RenderError> + Send + Sync;

/// One compared configuration: its name and its render settings.
///
/// The settings are a template the harness treats as opaque: it overrides only the fields
/// every comparison controls — `width`, `height` (the experiment's size), `budget` (the
/// regime), `seed` and `threads` — and leaves the integrator and its own settings as the
/// method gave them. The template is a value ([`Method::new`]) or comes from a closure of the
/// [`RunContext`] ([`Method::from_fn`]), e.g. a step size tuned per scene beforehand.
///
/// # Example
/// ```
/// use experiments::Method;
/// use render::session::{IntegratorKind, RenderSettings};
///
/// let pt = Method::new(
///     "PT",
///     RenderSettings { method: IntegratorKind::Pt.settings(), ..RenderSettings::default() },
/// )
/// .with_parameter("integrator", "pt");
/// assert_eq!((pt.name(), pt.slug()), ("PT", "PT"));
/// assert_eq!(Method::new("p_l=0.1", RenderSettings::default()).slug(), "p_l_0_1");
/// ```
pub struct Method {
    name: String,
    slug: String,
    parameters: Vec<(String, String)>,
    settings: Box<SettingsFn>,
    renderer: Option<Box<RenderFn>>,
    baseline: Option<String>,
}

impl Method {
    /// A method rendering with `template` for every scene and seed.
    #[must_use]
    pub fn new(name: impl Into<String>, template: RenderSettings) -> Self {
        Self::from_fn(name, move |_| template.clone())
    }

    /// A method whose settings template depends on where it runs.
    #[must_use]
    pub fn from_fn(
        name: impl Into<String>,
        settings: impl Fn(&RunContext<'_>) -> RenderSettings + Send + Sync + 'static,
    ) -> Self {
        let name = name.into();
        Self {
            slug: slug(&name),
            name,
            parameters: Vec::new(),
            settings: Box::new(settings),
            renderer: None,
            baseline: None,
        }
    }

    /// Adds a parameter shown with the method in the report (e.g. `large step`, `fixed 0.3`).
    #[must_use]
    pub fn with_parameter(mut self, key: impl Into<String>, value: impl fmt::Display) -> Self {
        self.parameters.push((key.into(), value.to_string()));
        self
    }

    /// Sets the file stem of the method's images (default: the name with every character
    /// other than an ASCII letter or digit replaced by `_`).
    #[must_use]
    pub fn with_slug(mut self, slug: impl Into<String>) -> Self {
        self.slug = slug.into();
        self
    }

    /// Renders with `renderer` instead of [`render::session::render`] (for a method the
    /// session cannot express yet; it receives the resolved settings).
    #[must_use]
    pub fn with_renderer(
        mut self,
        renderer: impl Fn(&Scene, &RenderSettings) -> Result<RenderOutput, RenderError>
            + Send
            + Sync
            + 'static,
    ) -> Self {
        self.renderer = Some(Box::new(renderer));
        self
    }

    /// Compares this method with `baseline` in the tables' ratio column instead of the
    /// experiment's baseline (e.g. each perturbation against its own non-adaptive run).
    #[must_use]
    pub fn with_baseline(mut self, baseline: impl Into<String>) -> Self {
        self.baseline = Some(baseline.into());
        self
    }

    /// The name shown in tables and the report.
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The file stem of the method's images.
    #[must_use]
    pub fn slug(&self) -> &str {
        &self.slug
    }

    /// The method's own parameters, in the order given.
    #[must_use]
    pub fn parameters(&self) -> &[(String, String)] {
        &self.parameters
    }

    /// The baseline set with [`Method::with_baseline`].
    #[must_use]
    pub fn baseline(&self) -> Option<&str> {
        self.baseline.as_deref()
    }

    /// The settings of a render at `context`: the method's template with `width`, `height`,
    /// `budget`, `seed` and `threads` set from the context.
    #[must_use]
    pub fn settings(&self, context: &RunContext<'_>) -> RenderSettings {
        RenderSettings {
            width: context.size,
            height: context.size,
            budget: context.regime.budget(),
            seed: context.seed,
            threads: context.threads,
            ..(self.settings)(context)
        }
    }

    /// Renders `scene` with `settings` (see [`Method::with_renderer`]).
    pub(crate) fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
    ) -> Result<RenderOutput, RenderError> {
        match &self.renderer {
            Some(renderer) => renderer(scene, settings),
            None => render(scene, settings, &NoProgress, &AtomicBool::new(false)),
        }
    }
}

impl fmt::Debug for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Method")
            .field("name", &self.name)
            .field("slug", &self.slug)
            .field("parameters", &self.parameters)
            .field("custom_renderer", &self.renderer.is_some())
            .field("baseline", &self.baseline)
            .finish_non_exhaustive()
    }
}

/// `name` with every character other than an ASCII letter or digit replaced by `_`.
fn slug(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

#[cfg(test)]
mod tests {
    use render::session::{Budget, IntegratorKind};

    use super::*;

    fn context(previous: &[RunRecord]) -> RunContext<'_> {
        RunContext {
            scene: "cornell",
            regime: Regime::EqualSamples(8),
            seed: 42,
            size: 16,
            threads: 3,
            previous,
        }
    }

    #[test]
    fn harness_fields_override_the_template_and_nothing_else() {
        let template = RenderSettings {
            method: IntegratorKind::Bdpt.settings(),
            width: 999,
            height: 7,
            budget: Budget::SamplesPerPixel(1000),
            threads: 64,
            seed: 5,
            max_depth: 9,
        };
        let s = Method::new("BDPT", template).settings(&context(&[]));
        assert_eq!((s.width, s.height, s.seed, s.threads), (16, 16, 42, 3));
        assert_eq!(s.budget, Budget::SamplesPerPixel(8));
        assert_eq!((s.integrator(), s.max_depth), (IntegratorKind::Bdpt, 9));
    }

    #[test]
    fn closures_see_the_context_and_slugs_are_file_safe() {
        let m = Method::from_fn("depth = scene", |c| RenderSettings {
            max_depth: if c.scene == "cornell" { 3 } else { 8 },
            ..RenderSettings::default()
        });
        assert_eq!(m.settings(&context(&[])).max_depth, 3);
        assert_eq!(m.slug(), "depth___scene");
        assert_eq!(m.with_slug("d").slug(), "d");
    }

    #[test]
    fn methods_are_send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<Method>();
    }
}
