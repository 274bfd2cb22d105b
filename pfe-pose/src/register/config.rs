//! The registration's settings.

/// Settings of the registration.
///
/// ```
/// let c = pfe_pose::Config::default();
/// assert!(c.max_rotation > 1.4 && c.max_translation >= 1800.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Config {
    /// Largest translation between two scans considered (from the prior's pose, if any), mm.
    pub max_translation: f32,
    /// Largest rotation between two scans considered (from the prior's pose, if any), rad.
    pub max_rotation: f32,
    /// Model noise added to every line: (σ_α rad, σ_ρ mm). Covers what the range noise does
    /// not: walls that are not perfectly straight, partial views, the extraction's choices.
    pub line_floor: [f32; 2],
    /// Model noise added to every point feature, σ per axis, mm.
    pub point_floor: f32,
    /// Lines closer than this to parallel (rad) do not make a hypothesis pair.
    pub min_pair_angle: f32,
    /// χ²₂ gate for a match (9.21: 99 %).
    pub gate: f32,
    /// χ²₃ gate of a hypothesis against the prior.
    pub prior_gate: f32,
    /// Slack for a hypothesis's own error while scoring: (σ_α rad, σ_ρ mm, σ per mm of reach).
    pub slack: [f32; 3],
    /// Segments farther apart along their line than this (mm) do not match.
    pub overlap_slack: f32,
    /// A direction whose standard deviation (x, y in mm; θ in units of
    /// [`ROTATION_SCALE`](super::ROTATION_SCALE)) exceeds this is one the scene cannot tell, mm.
    pub degenerate_sigma: f32,
    /// Weight of the segments' overlap in a line match's score (0: none; 1: a match counts in
    /// proportion to how much of the shorter segment the other covers).
    pub overlap_weight: f32,
    /// Weight of the visibility check in the choice among refined hypotheses: each segment
    /// that would hide, seen from the other scan, what that scan saw costs up to this much
    /// score (0: no check).
    pub visibility_weight: f32,
    /// Least score (matches' agreement less the visibility penalty) for a registration.
    pub min_score: f32,
    /// Count a direction that a single match alone determines as unobservable (its
    /// information dropped): an association no other feature confirms is not trusted.
    pub confirm: bool,
    /// Line matches whose segments are both at least this long (mm) need no confirmation
    /// (see [`Config::confirm`]): a long wall is not mistaken for another.
    pub trusted_length: f32,
    /// Most hypotheses considered (within the bounds or the prior), in the order they are
    /// formed (the longest lines first): bounds the worst case. On the shared CARMEN logs a
    /// scan pair forms 177 (median) and at most 2250.
    pub max_hypotheses: u32,
    /// Hypotheses scored at most: the formed ones are clustered by pose (pairs of features
    /// that agree; at most 96 clusters) and this many clusters, the most supported first, are
    /// scored at their mean (besides the prior's pose, or no motion).
    pub scored: u32,
    /// Fewest matched features for a registration (two parallel line matches suffice in a
    /// corridor, as a degenerate one).
    pub min_matches: usize,
    /// Scale the covariance by the residuals' χ² per degree of freedom when above 1.
    pub scale_by_residuals: bool,
    /// Give up ([`Failure::Ambiguous`](super::Failure::Ambiguous)) when a distinct second solution scores at least this
    /// fraction of the best (above 1: never).
    pub ambiguity: f32,
    /// With the scans' points ([`crate::points`]): a refined hypothesis whose points' score
    /// ([`crate::points::Agreement::score`]) exceeds the features' winner's by more than this
    /// wins instead.
    pub verify_margin: f32,
    /// With the scans' points: the least points' score at which an answer is trusted. A
    /// point-to-line ICP's answer ([`crate::points::icp`]) is taken when its score reaches it;
    /// a features' winner reaching it is not ambiguous with a close runner-up; the odometry's
    /// search of the map, when the pair did not register, is refused below it. A pair's
    /// features' registration below it is not refused: the ICP's answer replaces it only when
    /// that agrees better ([`Config::verify_keep`]); an answer still below it is looked at
    /// again over the circle of headings ([`crate::points::register_scans`]).
    pub verify_accept: f32,
    /// With the scans' points: a registration whose points' score reaches this is kept
    /// without trying the ICP; below it, an ICP answer whose points agree better by
    /// [`Config::verify_margin`] replaces it.
    pub verify_keep: f32,
    /// With the scans' points: the odometry's tracking against the map is taken only when
    /// its points' score against the previous scan reaches this.
    pub verify_track: f32,
    /// With the scans' points: a registration degenerate by its features is resolved by the
    /// points' ICP when they determine every direction.
    pub points_resolve: bool,
}

impl Default for Config {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl Config {
    /// The default settings, as a constant (`Config::default()`).
    ///
    /// ```
    /// assert_eq!(pfe_pose::Config::DEFAULT, pfe_pose::Config::default());
    /// ```
    pub const DEFAULT: Config = Self {
        max_translation: 3000.0,
        max_rotation: 1.75,
        line_floor: [0.008, 15.0],
        point_floor: 15.0,
        min_pair_angle: 0.17,
        gate: 9.21,
        prior_gate: 16.27,
        slack: [0.05, 100.0, 0.03],
        overlap_slack: 500.0,
        degenerate_sigma: 300.0,
        overlap_weight: 0.5,
        visibility_weight: 1.0,
        min_score: 0.0,
        confirm: true,
        trusted_length: 1000.0,
        max_hypotheses: 4096,
        scored: 96,
        min_matches: 3,
        scale_by_residuals: true,
        ambiguity: 2.0,
        verify_margin: 0.08,
        verify_accept: 0.2,
        verify_keep: 0.85,
        verify_track: 0.85,
        points_resolve: true,
    };
}
