// Surface texture metrology, independent of how the surface was made: profiles (the ISO
// 16610-21 Gaussian and ISO 16610-31 robust filters, ISO 21920-2 parameters, the ISO 21920-3
// default cut-off, read from CSV), areal surfaces (`HeightMap`: the ISO 16610-61 filter by FFT
// with FFTW, form removal, ISO 25178-2 parameters, comparison of two surfaces) and X3P files
// (ISO 5436-2: libzip, pugixml, nettle's MD5). Heights and lengths mm. docs/models.md.
#pragma once

#include <cstddef>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace trochomill {

// ---- surface texture of a profile (ISO 16610-21 filter, ISO 21920-2 parameters) ----------

/// How the Gaussian filter treats the profile's ends, where its weighting function (+-lambda)
/// reaches past the data.
enum class FilterEnds {
  /// The mean line only where the whole weighting function lies on the profile: one cut-off
  /// at each end is dropped (run-in and run-out, as on a stylus instrument's traverse).
  discard,
  /// Over the whole profile, the weights that lie on it renormalised to sum to one (the
  /// zero-order Gaussian regression of ISO 16610-28's end-effect correction).
  normalize,
};

/// A profile split by the ISO 16610-21 Gaussian filter: the mean line (wavelengths longer than
/// the cut-off, transmitted at exp(-pi (alpha lambda_c / lambda)^2), 50 % at lambda_c, alpha =
/// sqrt(ln 2 / pi)) and the residual (the profile less its mean line), on the span of the
/// input the filter covers (`first`..`first + mean_mm.size()` of the input samples).
struct FilteredProfile {
  std::size_t first = 0;            ///< index of the first output sample in the input
  std::vector<double> mean_mm;      ///< mean line (long-wave part), mm
  std::vector<double> residual_mm;  ///< profile less mean line (short-wave part), mm
};

/// Filters heights `z_mm` sampled every `dx_mm` with cut-off `cutoff_mm` (the weighting
/// function truncated at +-cutoff, where it is 6.5e-7 of its peak; weights normalised).
/// Throws InputError for non-finite or non-positive dx or cut-off, a non-finite height, a
/// cut-off under 2 dx, or (discard) a profile shorter than 2 cut-offs plus a sample.
[[nodiscard]] FilteredProfile gaussian_filter(const std::vector<double>& z_mm, double dx_mm,
                                              double cutoff_mm,
                                              FilterEnds ends = FilterEnds::discard);

/// The robust Gaussian regression filter (ISO 16610-31, zero order): the mean line of the
/// Gaussian weights times Tukey's biweight of each sample's residual, delta = (1 - (r /
/// c)^2)^2 for |r| < c = 4.4 median |r| (else 0), iterated from the plain filter until the
/// mean line moves less than 1e-9 of the profile's range (at most 50 times). Deep scratches
/// and high peaks, which drag the plain filter's mean line, get no weight. Same inputs and
/// errors as gaussian_filter.
[[nodiscard]] FilteredProfile robust_gaussian_filter(const std::vector<double>& z_mm, double dx_mm,
                                                     double cutoff_mm,
                                                     FilterEnds ends = FilterEnds::discard);

/// The Gaussian filter's transmission of the long-wave part at wavelength `lambda_mm`.
[[nodiscard]] double gaussian_transmission(double lambda_mm, double cutoff_mm);

/// Profile parameters (ISO 21920-2, the successor of ISO 4287) of a profile that is already
/// the part to evaluate (an R profile: the residual of the lambda_c filter), heights in mm
/// about its mean line, sampled every dx_mm, over `sections` equal sampling lengths (5 by
/// default; the section-wise parameters are their mean).
struct ProfileParameters {
  double ra_mm = 0;  ///< arithmetic mean height |z|
  double rq_mm = 0;  ///< root mean square height
  double rsk = 0;    ///< skewness (Rq^-3 mean z^3)
  double rku = 0;    ///< kurtosis (Rq^-4 mean z^4)
  double rp_mm = 0;  ///< largest peak height, mean over the sections
  double rv_mm = 0;  ///< largest valley depth (positive), mean over the sections
  double rz_mm = 0;  ///< Rp + Rv per section, mean over the sections
  double rt_mm = 0;  ///< highest peak to lowest valley over the evaluation length
  /// mean width of the profile elements (a peak above and a valley below the mean line, each
  /// at least 10 % of Rz high and 1 % of the sampling length wide), mm; 0 without elements
  double rsm_mm = 0;
  int elements = 0;  ///< profile elements RSm is the mean of
  double evaluation_length_mm = 0;
  int sections = 0;
};
/// Throws InputError for fewer than 2 samples per section, bad dx or a non-finite height.
[[nodiscard]] ProfileParameters profile_parameters(const std::vector<double>& z_mm, double dx_mm,
                                                   int sections = 5);

/// The ISO 21920-3 (ISO 4288) default cut-off for a non-periodic profile of roughness Ra:
/// 0.08 mm up to Ra 0.02 um, 0.25 mm to 0.1 um, 0.8 mm to 2 um, 2.5 mm to 10 um, 8 mm above.
[[nodiscard]] double default_cutoff_mm(double ra_mm);

/// Roughness (R profile: the residual of the lambda_c filter, five cut-offs long) and waviness
/// (W profile: its mean line) of a profile, with the cut-off used.
struct ProfileTexture {
  double cutoff_mm = 0;
  /// How the cut-off was chosen: "given", or "ISO 21920-3 default from Ra" (found by
  /// iterating: Ra with 0.8 mm, the table's cut-off for it, again until it stays).
  std::string cutoff_source;
  ProfileParameters roughness;
  double wa_mm = 0;        ///< arithmetic mean height of the W profile about its mean
  double wt_mm = 0;        ///< total height of the W profile over the evaluation length
  double lambda_s_mm = 0;  ///< the S-filter's cut-off (0: none)
  bool robust = false;     ///< the mean line by the robust filter (ISO 16610-31)
  /// The evaluated R profile (the residual of the lambda_c filter) and W profile (its mean
  /// line), mm, every `profile_dx_mm` over the evaluation length; the first point lies
  /// `profile_start_mm` along the input from its first sample (for a periodic profile, along
  /// its endless repetition).
  std::vector<double> roughness_profile_mm, waviness_profile_mm;
  double profile_dx_mm = 0, profile_start_mm = 0;
};
/// How a measured profile is filtered besides the cut-off.
struct ProfileFilterOptions {
  /// The lambda_s filter (ISO 3274 / 21920-3): the primary profile is the Gaussian mean
  /// line of this cut-off (mm; none: the profile as given).
  std::optional<double> lambda_s_mm;
  bool robust = false;  ///< robust_gaussian_filter for the lambda_c mean line
};
/// The texture of one period of a periodic profile (heights every dx_mm; the sample after the
/// last would be the first again): repeated to a run-in, five cut-offs and a run-out, filtered
/// with `cutoff_mm` or the default for its Ra, evaluated over the five cut-offs.
[[nodiscard]] ProfileTexture periodic_profile_texture(const std::vector<double>& period_z_mm,
                                                      double dx_mm,
                                                      std::optional<double> cutoff_mm = {});
/// The same for an open profile (a measured trace): run-in and run-out of one cut-off each;
/// the evaluation length is what lies between (five cut-offs or what there is, at least one).
[[nodiscard]] ProfileTexture profile_texture(const std::vector<double>& z_mm, double dx_mm,
                                             std::optional<double> cutoff_mm = {},
                                             const ProfileFilterOptions& options = {});

/// A profile read from a file: heights (mm) every spacing (mm), and where it came from.
struct MeasuredProfile {
  std::vector<double> z_mm;
  double dx_mm = 0;
  std::string description;  ///< e.g. "left wall at z = -3.01 mm"
};
/// A profile from CSV text: the columns `x_column` and `z_column` (by header name; empty: the
/// first two columns), x in mm and z in mm times `z_to_mm` (1e-3 for um); x must increase in
/// equal steps (to 1e-6 of a step). Throws InputError naming source:line.
[[nodiscard]] MeasuredProfile read_profile_csv(std::string_view text, std::string_view source,
                                               const std::string& x_column = "",
                                               const std::string& z_column = "",
                                               double z_to_mm = 1.0);
/// One wall of a simulation's walls.csv (y_mm, z_mm, left_x_mm, right_x_mm: `simulate --out`)
/// along y at the level nearest `z_mm` (default: the middle level), material side up (+x on
/// the left wall, -x on the right). `machined_only`: the front arc where the simulation's
/// window ended is left out: the points with y above the last y less the wall's distance
/// from the slot's centre line (the largest |x| at that level: the cut front is an arc about
/// the centre line no longer along y than that radius, as the circular families' and the
/// ellipses' up to aspect ratio 1 are), and the description says where the profile ends. Throws
/// InputError naming source:line or what is missing (or, machined_only, when fewer than 3
/// points of wall are left: the window's walls are all front).
[[nodiscard]] MeasuredProfile read_wall_profile_csv(std::string_view text, std::string_view source,
                                                    bool left, std::optional<double> z_mm = {},
                                                    bool machined_only = false);

/// The material ratio (Abbott-Firestone) curve: the share of the evaluation length where the
/// profile is at or above height c, for heights from its top to its bottom (`points` values).
struct MaterialRatioCurve {
  std::vector<double> c_mm;           ///< height, top to bottom
  std::vector<double> ratio_percent;  ///< Rmr(c), 0 to 100
};
[[nodiscard]] MaterialRatioCurve material_ratio_curve(const std::vector<double>& z_mm,
                                                      int points = 101);

// ---- areal surface texture (ISO 16610-61 filter, ISO 25178-2 parameters) -----------------

/// A surface on a regular grid: heights (mm) at nx columns along x, every dx_mm, by ny rows
/// along y, every dy_mm; row-major, z_mm[row * nx + column]; the first point at (x0, y0) mm.
struct HeightMap {
  std::size_t nx = 0, ny = 0;
  double dx_mm = 0, dy_mm = 0;
  double x0_mm = 0, y0_mm = 0;
  std::vector<double> z_mm;
  std::string description;  ///< e.g. "floor, simulated" or the instrument's record
  [[nodiscard]] double at(std::size_t column, std::size_t row) const {
    return z_mm[row * nx + column];
  }
};
/// Throws InputError unless the map has at least 2 x 2 points, finite positive spacings, as
/// many heights as points and every height finite; `what` names it in the message.
void check_height_map(const HeightMap& map, std::string_view what);

/// The areal Gaussian filter (ISO 16610-61): the mean surface (wavelengths longer than the
/// nesting index `cutoff_mm`, transmitted as the profile filter's exp(-pi (alpha lambda_c /
/// lambda)^2) in each direction). The weighting function is separable, so it runs as the
/// profile filter along x, then along y, each line by FFT convolution (FFTW) when its kernel
/// is long; at the map's edges the weights on the map are renormalised (FilterEnds::normalize:
/// on a rectangle the 2-D renormalisation is the product of the two 1-D ones). Results do not
/// depend on the thread count. Throws InputError for a bad map, a cut-off under two spacings
/// in either direction or a kernel past 5e7 samples.
[[nodiscard]] HeightMap gaussian_filter_areal(const HeightMap& map, double cutoff_mm);

/// The F-operator: what is removed as the surface's form before the L-filter.
enum class FormRemoval {
  none,        ///< nothing (the mean height only)
  plane,       ///< the least-squares plane
  polynomial,  ///< the least-squares polynomial in x and y of total degree `degree` (1..6)
};
/// The map less its least-squares form (the fit on the full grid: separable sums, exact to
/// rounding). Throws InputError for a degree outside 1..6 with FormRemoval::polynomial.
[[nodiscard]] HeightMap remove_form(HeightMap map, FormRemoval form, int degree = 2);

/// Areal field parameters (ISO 25178-2) of a scale-limited surface, heights about its mean
/// plane (mm); the spacings give the area.
struct ArealParameters {
  double sa_mm = 0;  ///< arithmetic mean height
  double sq_mm = 0;  ///< root mean square height
  double ssk = 0;    ///< skewness
  double sku = 0;    ///< kurtosis
  double sp_mm = 0;  ///< largest peak height
  double sv_mm = 0;  ///< largest pit depth (positive)
  double sz_mm = 0;  ///< maximum height, Sp + Sv
  /// Developed interfacial area ratio, percent: each grid cell's area from the mean slopes
  /// of its edges, dx dy sqrt(1 + zx^2 + zy^2), summed, over the projected area, less one.
  double sdr_percent = 0;
  /// Autocorrelation length (mm): the shortest lag at which the areal autocorrelation
  /// function decays to 0.2, searched over directions (0.5 degree apart) out to half the
  /// map's extent; empty when it does not decay that far in any direction.
  std::optional<double> sal_mm;
  /// Texture aspect ratio: Sal over the longest decay length (0..1); empty when the
  /// autocorrelation does not decay to 0.2 within half the extent in every direction (a
  /// strongly directional texture: Str tends to 0).
  std::optional<double> str;
  double area_mm2 = 0;  ///< the evaluation area
  /// Flat to rounding (Sq within 1e-12 of the heights it came from): Ssk and Sku are 0 and
  /// Sal and Str empty.
  bool flat = false;
};
/// `autocorrelation`: compute Sal and Str (an FFT of the map padded by half its extent).
[[nodiscard]] ArealParameters areal_parameters(const HeightMap& surface,
                                               bool autocorrelation = true);

/// How the areal texture is separated: the S-filter (short wavelengths, optional), the
/// F-operator, the L-filter (the roughness surface is what it leaves).
struct ArealFilterOptions {
  std::optional<double> s_mm;  ///< S-filter nesting index, mm (none: no S-filter)
  /// L-filter nesting index, mm (none: ISO 21920-3's profile cut-off for the S-L surface's
  /// Sa, found by iteration as for a profile, and stated in the result)
  std::optional<double> l_mm;
  FormRemoval form = FormRemoval::plane;
  int degree = 2;  ///< polynomial degree with FormRemoval::polynomial
};
/// The texture of a surface: the S-F surface (S-filtered, form removed: roughness and
/// waviness) and the S-L surface (less the L-filter's mean surface: roughness), with the
/// filters used.
struct ArealTexture {
  double s_mm = 0;  ///< 0: no S-filter
  double l_mm = 0;
  std::string l_source;  ///< "given" or how the default was chosen
  FormRemoval form = FormRemoval::plane;
  int degree = 0;
  ArealParameters sf;  ///< S-F surface (without Sal and Str)
  ArealParameters sl;  ///< S-L surface
};
/// Throws InputError for a bad map or nesting indices the sampling cannot resolve (under two
/// spacings) or longer than the map's shorter side.
[[nodiscard]] ArealTexture areal_texture(const HeightMap& map, const ArealFilterOptions& options);

/// A measured surface against a predicted one, point by point.
struct SurfaceComparison {
  /// Where the predicted surface's point (x, y) was found on the measured one: measured(x +
  /// shift_x, y + shift_y) best matches predicted(x, y) (mm; a whole number of the measured
  /// spacings).
  double shift_x_mm = 0, shift_y_mm = 0;
  /// The best-fit plane taken out of the difference (measured - predicted): its mean (mm) and
  /// slopes (mm/mm): the two surfaces' set-up in height and tilt.
  double offset_mm = 0, tilt_x = 0, tilt_y = 0;
  /// Correlation of the two over the overlap, each less its plane there (1: the same shape).
  double correlation = 0;
  double overlap_mm2 = 0;                               ///< the area compared
  std::size_t points = 0;                               ///< measured points compared
  double rms_difference_mm = 0, max_difference_mm = 0;  ///< after the plane, over the overlap
  ArealParameters measured, predicted;  ///< over the overlap, each less its own plane
};
/// Aligns `predicted` to `measured` and compares them on the measured grid: the predicted
/// surface is resampled there (bilinear), the shift is the one of largest normalised
/// cross-correlation (both less their planes; by FFT, shifts up to `max_shift_mm` each way,
/// default a quarter of the measured map's shorter side; an overlap of at least half the
/// smaller map), then the best-fit plane of the difference is removed. Throws InputError for
/// bad maps or when no shift leaves enough overlap.
[[nodiscard]] SurfaceComparison compare_surfaces(const HeightMap& measured,
                                                 const HeightMap& predicted,
                                                 std::optional<double> max_shift_mm = {});

[[nodiscard]] const char* form_removal_name(FormRemoval form);

// ---- X3P (ISO 5436-2, openGPS): the exchange format of stylus and optical instruments ------

/// What an X3P file says of the data besides the heights (its Record2).
struct X3pInfo {
  std::string date;     ///< ISO 8601; empty: SOURCE_DATE_EPOCH (if set) or now, in UTC
  std::string creator;  ///< who or what made it
  std::string manufacturer = "trochomill", model, serial = "-", version;
  std::string probing = "Software";  ///< Contacting, NonContacting or Software
  std::string comment;
};

/// Writes a height map (or, with ny = 1, a profile) as an X3P file: main.xml (ISO5436_2 schema,
/// lengths in metres), bindata/data.bin (little-endian doubles, x fastest) with its MD5 in
/// main.xml, and md5checksum.hex (the MD5 of main.xml). Throws InputError for a bad map,
/// IoError when the file cannot be written.
void write_x3p(const std::filesystem::path& file, const HeightMap& map, const X3pInfo& info = {});

/// Reads an X3P file: a surface (FeatureType SUR) or a profile (PRF, ny = 1) on incremental
/// x and y axes, heights of any of the format's types (int16, int32, float, double; scaled by
/// CZ's increment and offset) from bindata or listed in main.xml, in mm. Checks the data's
/// MD5 when main.xml gives one. Throws InputError naming the file (and main.xml's line:column
/// for XML errors) for what is not a valid X3P file, and for what it cannot use: point clouds
/// (absolute axes), several layers, and points marked invalid (it needs complete maps).
/// `max_points`: a larger map is refused before its data is read (the caller's memory limit).
[[nodiscard]] HeightMap read_x3p(const std::filesystem::path& file, X3pInfo* info = nullptr,
                                 double max_points = 268435456.0);

}  // namespace trochomill
