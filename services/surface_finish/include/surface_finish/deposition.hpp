#pragma once
// The spray deposition model and its measurement (paper section 6.2, Table 2). No DDS.
//
// The nozzle (the TCP) emits a cone of half-angle alpha along its z axis with a flux uniform
// per solid angle; a wall cell inside the cone gains Q dt cos(phi) / (Omega r^2) of film (r the
// distance from the nozzle, phi the ray's angle to the wall normal, Omega = 2 pi (1 - cos
// alpha)), i.e. a disc of radius standoff * tan(alpha) when the nozzle faces the wall. The
// film is normalised to the nominal coat: the thickness at a stroke's centre line when the
// nozzle passes at the planned standoff and speed (1.0). A cell is painted where the film is
// at least `visible` (0.1) of that. Per stroke (each stroke's film kept apart): the coat width
// (painted extent across the stroke, median over heights in its middle 60 %), the heights of
// its lower and upper ends on its centre line; between adjacent strokes the difference of
// their lower ends (delta h, the paper's start error) and of their upper ends; the coverage of
// the rectangle and the painted area outside it (overspray).

#include <Eigen/Geometry>

#include <string>
#include <vector>

#include "surface_finish/types.hpp"

namespace concert::surface_finish {

struct DepositionParams {
  double cell{0.002};      ///< coverage map resolution [m]
  double margin{0.15};     ///< map extends this far beyond the rectangle [m]
  double visible{0.1};     ///< painted threshold, fraction of the nominal coat
};

/// Measures of one stroke's coat [m].
struct CoatMeasure {
  double x{0.0};          ///< planned lateral position
  double width{0.0};      ///< median painted width across the stroke
  double width_min{0.0};
  double width_max{0.0};
  double bottom{0.0};     ///< lowest painted height on the centre line
  double top{0.0};        ///< highest
  bool up{true};          ///< painted upwards
};

/// The report of one spray run.
struct SprayReport {
  Rect rect;
  double coat_width_nominal{0.0};  ///< [m]
  std::vector<CoatMeasure> coats;
  std::vector<double> delta_bottom;  ///< bottom[i + 1] - bottom[i] [m]
  std::vector<double> delta_top;     ///< top[i + 1] - top[i] [m]
  double coverage{0.0};              ///< painted fraction of the rectangle [0, 1]
  double overspray_area{0.0};        ///< painted area outside the rectangle [m^2]
  double max_abs_delta_h{0.0};       ///< largest |delta_bottom| [m]
  double max_width_error{0.0};       ///< largest |coat width - nominal| [m]
  double thickness_mean{0.0};        ///< mean film in the rectangle (nominal coats)
  double thickness_cv{0.0};          ///< its coefficient of variation
};

/// The coverage map of one run.
class SprayDeposition {
 public:
  /// A map over `rect` (plus the margin) on `wall`, for `strokes` strokes, the tool's cone,
  /// the planned standoff and speed (the nominal coat). Throws FinishError for bad sizes.
  SprayDeposition(const WallFrame& wall, const Rect& rect, const ToolSpec& tool, double speed, int strokes,
                  DepositionParams params = {});

  /// Adds the spray of a nozzle at `tcp` (base frame) for `dt` [s] to stroke `stroke`'s film
  /// (ignored when stroke < 0: the tool is off on joins).
  void add(const Eigen::Isometry3d& tcp, double dt, int stroke);

  /// Measures the map against the strokes' planned positions and directions.
  [[nodiscard]] SprayReport measure(const std::vector<double>& stroke_x, const std::vector<bool>& stroke_up) const;

  /// The report as JSON text (every length in mm, fractions in %).
  [[nodiscard]] static std::string to_json(const SprayReport& report);
  /// Writes the coverage map as a PNG (film as a colour map, the rectangle outlined, unpainted
  /// cells inside it in red). Throws FinishError if it cannot write.
  void write_png(const std::string& path) const;

  [[nodiscard]] int cols() const { return nx_; }
  [[nodiscard]] int rows() const { return ny_; }
  /// Total film at cell (ix, iy) (iy from the bottom), nominal coats.
  [[nodiscard]] double film(int ix, int iy) const;

 private:
  [[nodiscard]] double stroke_film(int s, int ix, int iy) const;
  WallFrame wall_;
  Rect rect_;
  ToolSpec tool_;
  DepositionParams params_;
  double x0_{0.0}, y0_{0.0};  ///< wall coordinates of cell (0, 0)'s centre
  int nx_{0}, ny_{0};
  double nominal_{1.0};       ///< film of one nominal pass (raw units)
  std::vector<std::vector<float>> per_stroke_;
};

}  // namespace concert::surface_finish
