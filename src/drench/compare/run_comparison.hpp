#pragma once
/// A run's saved frames against a reference run's at the same times (issue 42): observables a user can see
/// (where the cloth is, how much water it holds, where the water is), each with its unit, and per run the
/// largest relative error over the frames. The density error a run reports is the pressure solver's residual,
/// not how right the result is; these are. Bullet-free: it reads the frame files (docs/output.md) only.

#include <string>
#include <vector>

#include <drench/common/types.hpp>

namespace drench {

/// The frames of one run as the comparison reads them; scene/run_frames.hpp fills it from a run folder.
struct RunFrames {
  std::string dir;                       ///< the run folder, for messages
  Scalar particle_mass = 0;              ///< every particle's mass (unit: kg), > 0: rest_density x spacing^3
  Scalar particle_spacing = 0;           ///< (unit: m), > 0
  std::vector<double> times;             ///< the simulated time of each frame (unit: s), frame n at index n
  std::vector<std::string> fluid_files;  ///< frames/fluid_NNNN.ply, one per frame
  std::vector<std::string> cloth_files;  ///< frames/cloth_NNNN.ply, one per frame; empty without a cloth
  /// The water kill regions had removed by each frame, summed from the start (unit: kg), one per frame, or
  /// empty for none (a scene without kill regions). It is in no frame file, yet a run that loses more water
  /// than the reference must show it.
  std::vector<double> killed_kg;
};

/// What is compared, and how coarsely.
struct ComparisonSettings {
  /// Edge of the cubic cells of the mass grid (unit: m), >= 0; 0: four of the reference's particle spacings
  /// (2 cm for the jet's 5 mm particles). Cells must hold several particles, or the L1 difference only says
  /// that no two particles sit in the same place.
  Scalar cell_size = 0;
  /// Water counts as held by the cloth when it is above the cloth, seen along -y, by at most this (unit: m),
  /// > 0. The default, 2 cm, is a few particles' depth at the jet's 5 mm spacing: a puddle, not a splash.
  Scalar held_band = 0.02;
  std::vector<Scalar> gauges_x;  ///< dam break: x of each water-height gauge (unit: m); empty: none
  Scalar gauge_width = 0;  ///< width in x of a gauge's column (unit: m), >= 0; 0: the reference's spacing
  /// Depth in z of the channel a gauge's column spans (unit: m), >= 0; 0: the z extent of the reference's
  /// frame-0 water plus one spacing (each particle stands for a spacing cube). A gauge's height is the
  /// water's volume in its column over width x depth, so this must be the channel's when the water spreads
  /// in z beyond where it started.
  Scalar gauge_depth = 0;
  /// A run with fewer frames than the reference (one that stopped: a blow-up, a timeout) is compared over the
  /// frames it has; else that is an error.
  bool allow_shorter = false;
  /// Largest difference of a frame's time between the run and the reference (unit: s): the frames must
  /// show the same instant, or the error measured is the flow's motion in between.
  double time_tolerance = 1e-6;
};

/// One observable of one run against the reference.
struct ObservableError {
  std::string name;  ///< the sweep.csv column, its unit in the name, e.g. "cloth_rms_m"
  /// Per compared frame, the difference from the reference (unit: the name's; >= 0).
  std::vector<double> per_frame;
  double largest = 0;     ///< max of per_frame (unit: the name's)
  double normaliser = 0;  ///< what `relative` divides by (unit: the name's), > 0 or NaN when there is none
  double relative = 0;    ///< largest / normaliser; NaN when the normaliser is 0
};

/// A run against the reference.
struct RunComparison {
  std::size_t frames = 0;                    ///< frames compared (the run's, when shorter and allowed)
  std::vector<ObservableError> observables;  ///< those the two runs have, in observable_names() order
  std::string worst;          ///< the name of the one with the largest relative error; "" when none has one
  double worst_relative = 0;  ///< its relative error; NaN when none has one
  /// Observables over time (unit: as named): the run's over the frames compared, the reference's over all of
  /// its frames; "centre_sag_m", "held_kg", "past_edges_kg" (killed included), "fluid_kg" (in the frame),
  /// "killed_kg", "front_m" (NaN where the scene has no such thing).
  std::vector<std::vector<double>> run_series, reference_series;
  std::vector<std::string> series_names;
};

/// Every observable the comparison can report, in order: the cloth's node distances (RMS and largest, each
/// node against the same node of the reference: same mesh required) and its centre sag (the y drop, from
/// frame 0, of the node nearest the mean of the reference's frame-0 nodes); the water held by the cloth
/// (particles above the cloth seen along -y, by at most `held_band`) and the water past its edges (particles
/// below the cloth's lowest node, through the cloth included, which the leak audit counts apart, plus the
/// water kill regions removed: it left the scene); the L1 difference of the fluid's mass over cubic cells of
/// `cell_size`, the killed water as one more cell; without a cloth, the surge front (the
/// largest x of a particle) and with gauges the water heights (the water's rest volume in a column of
/// `gauge_width` around each gauge, sum of m_j / rho0 = N spacing^3, over the column's cross-section
/// `gauge_width` x `gauge_depth`: a droplet thrown high moves it by one particle's volume, where the highest
/// particle would jump to the droplet; 0 for an empty column), the largest difference over the gauges.
/// Normalisers, from all of the reference's frames (a run that stopped early is not measured against the
/// small motion of the start): cloth distances and sag by the reference's largest centre sag; masses by the
/// reference's largest water mass over the frames (the frame's plus the killed); the front by its travel
/// (last minus first frame); gauge heights by the reference's largest gauge height.
const std::vector<std::string>& observable_names();

/// The observables compare_runs reports for a reference with or without a cloth, and with or without
/// gauges, in observable_names() order: with a cloth the cloth's distances and sag, the water held and past
/// its edges; without one the surge front; the mass difference always; the gauge height with gauges.
std::vector<std::string> reported_observables(bool cloth, bool gauges);

/// Checks `settings` against the reference they will measure, so that a sweep refuses them before any run.
/// @throws SceneError naming the setting (and drench sweep's option for it) and the value: cell_size not 0
///         and not in [the reference's particle spacing, kMaxCoordinate] (smaller cells each hold at most
///         one particle, and the difference says nothing of where the water is), held_band not in
///         (0, kMaxCoordinate], gauge_width or gauge_depth not 0 and not in (0, kMaxCoordinate], a gauge's x
///         not finite or beyond kMaxCoordinate, time_tolerance not in [0, 1] s.
void check_comparison_settings(const ComparisonSettings& settings, const RunFrames& reference);

/// Compares `run` with `reference` frame by frame.
/// @throws IoError naming the file or folder: a frame file that is missing or unreadable (read_ply's
///         errors), a run with more frames than the reference, or fewer when not `allow_shorter`, a frame
///         whose time differs from the reference's by over `time_tolerance` (both times named), a cloth in
///         one run and not the other, cloths whose node counts differ (both files named), or `killed_kg`
///         neither empty nor one per frame.
/// @throws SceneError for settings out of range (check_comparison_settings).
RunComparison compare_runs(const RunFrames& run, const RunFrames& reference,
                           const ComparisonSettings& settings);

}  // namespace drench
