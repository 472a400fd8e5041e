#include "experiments/config/config.h"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "fovea/params.h"

namespace experiments {
namespace {

std::string FormatNumber(double v) { return rig::FormatParamNumber(v); }

std::string Range(const ConfigParam& p) {
  if (std::holds_alternative<std::string*>(p.target) && !p.spec->choices) return "any text";
  return rig::RangeText(*p.spec, std::holds_alternative<bool*>(p.target));
}

// Valid UTF-8 with no control character but tab and newline: the text a
// string parameter may hold, which a YAML dump writes and reads back exactly.
bool IsPlainText(const std::string& text) {
  for (size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    int n = 0;  // continuation bytes
    if (c >= 0xc2 && c <= 0xdf)
      n = 1;
    else if (c >= 0xe0 && c <= 0xef)
      n = 2;
    else if (c >= 0xf0 && c <= 0xf4)
      n = 3;
    else if (c >= 0x80)
      return false;
    if (i + n >= text.size()) return false;
    unsigned long code = n == 0 ? c : c & (0x7f >> (n + 1));
    for (int k = 1; k <= n; ++k) {
      const auto cc = static_cast<unsigned char>(text[i + k]);
      if ((cc & 0xc0) != 0x80) return false;
      code = (code << 6) | (cc & 0x3f);
    }
    const bool control = code < 0x20 ? code != '\t' && code != '\n' : code >= 0x7f && code < 0xa0;
    // Control characters, overlong forms, surrogates, past U+10FFFF.
    if (control || (n == 2 && code < 0x800) || (n == 3 && (code < 0x10000 || code > 0x10ffff)) ||
        (code >= 0xd800 && code <= 0xdfff))
      return false;
    i += n + 1;
  }
  return true;
}

// `label` names the parameter in messages: "key 'idr.sigma'" or "--sigma".
void Assign(const ConfigParam& p, const std::string& text, const std::string& label) {
  auto fail = [&](const std::string& why) { throw UsageError(label + ": " + why); };
  const std::string shown = "'" + rig::ClipForMessage(text) + "'";
  if (auto* b = std::get_if<bool*>(&p.target)) {
    if (text == "true")
      **b = true;
    else if (text == "false")
      **b = false;
    else
      fail("expected true or false, got " + shown);
    return;
  }
  if (auto* s = std::get_if<std::string*>(&p.target)) {
    try {
      rig::CheckParam(*p.spec, text);
    } catch (const rig::InputError&) {
      fail(shown + " is not " + Range(p));
    }
    if (!IsPlainText(text))
      fail("expected UTF-8 text without control characters (tabs and newlines aside)");
    **s = text;
    return;
  }
  const std::optional<double> v = ParseNumber(text);
  if (!v) fail("expected a number, got " + shown);
  const bool integral = !std::holds_alternative<double*>(p.target);
  if (integral && *v != std::floor(*v)) fail("expected a whole number, got " + shown);
  if (*v < p.spec->lo || *v > p.spec->hi)
    fail(rig::ClipForMessage(text) + " is out of range " + Range(p));
  // Written as digits, a whole number is compared exactly: a double rounds
  // 2^53 + 1 down to 2^53.
  long long exact = 0;
  const auto digits = std::from_chars(text.data(), text.data() + text.size(), exact);
  if (integral && digits.ptr == text.data() + text.size() &&
      (digits.ec != std::errc() || exact < static_cast<long long>(p.spec->lo) ||
       exact > static_cast<long long>(p.spec->hi)))
    fail(rig::ClipForMessage(text) + " is out of range " + Range(p));
  if (auto* d = std::get_if<double*>(&p.target))
    **d = *v;
  else if (auto* i = std::get_if<int*>(&p.target))
    **i = static_cast<int>(*v);
  else if (auto* u = std::get_if<uint64_t*>(&p.target))
    **u = static_cast<uint64_t>(*v);
}

std::string ValueText(const ConfigParam& p) {
  if (auto* b = std::get_if<bool*>(&p.target)) return **b ? "true" : "false";
  if (auto* s = std::get_if<std::string*>(&p.target)) return (*s)->empty() ? "\"\"" : **s;
  if (auto* d = std::get_if<double*>(&p.target)) return FormatNumber(**d);
  if (auto* i = std::get_if<int*>(&p.target)) return std::to_string(**i);
  return std::to_string(**std::get_if<uint64_t*>(&p.target));
}

// The value as YAML text that reads back the same: a string stays plain
// only where YAML reads it back unchanged as a value (no '#', ': ', newline,
// leading space, null word); else it is double-quoted with escapes.
std::string YamlValueText(const ConfigParam& p) {
  auto* s = std::get_if<std::string*>(&p.target);
  if (!s) return ValueText(p);
  YAML::Emitter plain;
  plain << **s;
  static const std::set<std::string> kNullWords = {"", "~", "null", "Null", "NULL"};
  if (plain.c_str() == **s && !kNullWords.count(**s)) return **s;
  YAML::Emitter quoted;
  quoted << YAML::DoubleQuoted << **s;
  return quoted.c_str();
}

}  // namespace

std::optional<double> ParseNumber(const std::string& text) {
  double v = 0;
  const char* b = text.data();
  const auto r = std::from_chars(b, b + text.size(), v);
  if (r.ec != std::errc() || r.ptr != b + text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

namespace {

// The run itself: scene, seed, method, matcher.
void AddTopParams(RunConfig* c, std::vector<ConfigParam>* params) {
  namespace ep = params;
  params->insert(params->end(), {
                                    {&ep::kScene, &c->scene},
                                    {&ep::kSeed, &c->seed},
                                    {&ep::kMethod, &c->method},
                                    {&ep::kMatcher, &c->matcher},
                                });
}

// The rig: the simulated TAVT, the hardware rig, the sensor.
void AddRigParams(RunConfig* c, std::vector<ConfigParam>* params) {
  namespace sp = sim::params;
  namespace ep = params;
  sim::SimRigConfig& r = c->rig;
  RunConfig::Hardware& h = c->hardware;
  params->insert(params->end(), {
                                    {&sp::kWidthPx, &r.width_px},
                                    {&sp::kHeightPx, &r.height_px},
                                    {&sp::kHorizontalFovDeg, &r.horizontal_fov_deg},
                                    {&sp::kOpticalCentreXM, &r.optical_centre_offset_m.x()},
                                    {&sp::kOpticalCentreYM, &r.optical_centre_offset_m.y()},
                                    {&sp::kOpticalCentreZM, &r.optical_centre_offset_m.z()},
                                    {&sp::kCarriageMinM, &r.carriage_min_m},
                                    {&sp::kCarriageMaxM, &r.carriage_max_m},
                                    {&sp::kHomeBaselineM, &r.home_baseline_m},
                                    {&sp::kPanLimitDeg, &r.pan_limit_deg},
                                    {&sp::kTiltLimitDeg, &r.tilt_limit_deg},
                                    {&sp::kBaselineStepsPerMm, &r.baseline_steps_per_mm},
                                    {&sp::kPanTiltStepsPerDeg, &r.pan_tilt_steps_per_deg},
                                    {&sp::kSettleToleranceSteps, &r.settle_tolerance_steps},
                                    {&sp::kMoveTimeoutS, &r.move_timeout_s},
                                    {&ep::kRigType, &h.type},
                                    {&ep::kPort, &h.port},
                                    {&ep::kBaud, &h.baud},
                                    {&ep::kEmulateStages, &h.emulate_stages},
                                    {&ep::kUnits, &h.units},
                                    {&ep::kDirections, &h.directions},
                                    {&ep::kLeftCamera, &h.left_camera},
                                    {&ep::kRightCamera, &h.right_camera},
                                    {&ep::kCalibration, &r.calibration},
                                    {&ep::kFrameTimeoutS, &h.frame_timeout_s},
                                    {&ep::kBaselineVelocityMS, &h.baseline_velocity_m_s},
                                    {&ep::kPanTiltVelocityRadS, &h.pan_tilt_velocity_rad_s},
                                    {&sp::kRecordDir, &r.record_dir},
                                    {&sp::kNoiseSigmaDn, &r.noise.read_noise_sigma_dn},
                                    {&sp::kBlurSigmaPx, &r.noise.blur_sigma_px},
                                });
  sim::Imperfections& im = r.imperfections;
  params->insert(params->end(), {
                                    {&sp::kLeftMountRollDeg, &im.left.mount_rpy_deg.x()},
                                    {&sp::kLeftMountPitchDeg, &im.left.mount_rpy_deg.y()},
                                    {&sp::kLeftMountYawDeg, &im.left.mount_rpy_deg.z()},
                                    {&sp::kRightMountRollDeg, &im.right.mount_rpy_deg.x()},
                                    {&sp::kRightMountPitchDeg, &im.right.mount_rpy_deg.y()},
                                    {&sp::kRightMountYawDeg, &im.right.mount_rpy_deg.z()},
                                    {&sp::kLeftPanZeroDeg, &im.left.pan_zero_deg},
                                    {&sp::kLeftTiltZeroDeg, &im.left.tilt_zero_deg},
                                    {&sp::kRightPanZeroDeg, &im.right.pan_zero_deg},
                                    {&sp::kRightTiltZeroDeg, &im.right.tilt_zero_deg},
                                    {&sp::kDistortionK1, &im.k1},
                                    {&sp::kDistortionK2, &im.k2},
                                    {&sp::kDistortionP1, &im.p1},
                                    {&sp::kDistortionP2, &im.p2},
                                    {&sp::kLeftGain, &im.left.gain},
                                    {&sp::kRightGain, &im.right.gain},
                                    {&sp::kLeftOffsetDn, &im.left.offset_dn},
                                    {&sp::kRightOffsetDn, &im.right.offset_dn},
                                    {&sp::kVignetting, &im.vignetting},
                                    {&sp::kPositionErrorSteps, &im.position_error_steps},
                                });
}

// The fixation loop.
void AddLoopParams(RunConfig* c, std::vector<ConfigParam>* params) {
  namespace fp = fovea::params;
  fovea::FoveaOptions& f = c->fovea;
  params->insert(params->end(), {
                                    {&fp::kLoopFixations, &f.fixations},
                                    {&fp::kLoopStayInIdrView, &f.stay_in_idr_view},
                                    {&fp::kLoopFixateHoles, &f.fixate_holes},
                                    {&fp::kLoopPrescreenHoles, &f.prescreen_holes},
                                    {&fp::kLoopHoleFarFactor, &f.hole_far_factor},
                                    {&fp::kLoopStallFixations, &f.stall_fixations},
                                    {&fp::kLoopStallGrowth, &f.stall_growth},
                                    {&fp::kLoopAttemptsPerFixation, &f.attempts_per_fixation},
                                });
}

// Initial depth recovery.
void AddIdrParams(RunConfig* c, std::vector<ConfigParam>* params) {
  namespace fp = fovea::params;
  fovea::FoveaOptions& f = c->fovea;
  params->insert(params->end(),
                 {
                     {&fp::kIdrLogSigmaPx, &f.idr.zero_crossings.sigma_px},
                     {&fp::kIdrLogMinSlope, &f.idr.zero_crossings.min_slope},
                     {&fp::kIdrOrientationToleranceRad, &f.idr.matching.orientation_tolerance_rad},
                     {&fp::kIdrTakeNearest, &f.idr.matching.take_nearest_when_ambiguous},
                     {&fp::kIdrUniqueShare, &f.idr.unique_share},
                     {&fp::kIdrZMinM, &f.idr.z_min_m},
                     {&fp::kIdrMaxSlantDeg, &f.idr.max_slant_deg},
                     {&fp::kIdrMaxExpansion, &f.idr.max_expansion},
                     {&fp::kIdrMinExpansion, &f.idr.min_expansion},
                     {&fp::kIdrVergentSearchPx, &f.idr.vergent_search_px},
                     {&fp::kIdrVergentBaselineM, &f.idr.vergent_baseline_m},
                     {&fp::kIdrMaxStages, &f.idr.max_stages},
                     {&fp::kIdrPatchSizePx, &f.idr.patch_size_px},
                     {&fp::kIdrDiscontinuityJumpPx, &f.idr.discontinuity_jump_px},
                     {&fp::kIdrInitialBaselineM, &f.idr.fixed_initial_baseline_m},
                     {&fp::kIdrFitMinSupport, &f.idr.plane_fit.min_support},
                     {&fp::kIdrFitTolerancePx, &f.idr.plane_fit.fit_tolerance_px},
                     {&fp::kIdrFitMinInlierShare, &f.idr.plane_fit.min_inlier_share},
                     {&fp::kIdrFitRequireQuadrants, &f.idr.plane_fit.require_quadrants},
                     {&fp::kIdrMaxViewAngleDeg, &f.idr.max_view_angle_deg},
                 });
}

// Vergence, servo, tessellation and foveal stereo.
void AddFovealParams(RunConfig* c, std::vector<ConfigParam>* params) {
  namespace fp = fovea::params;
  fovea::FoveaOptions& f = c->fovea;
  fovea::FixationOptions& x = c->fovea.fixation;
  params->insert(params->end(),
                 {
                     {&fp::kFovealBaselineM, &x.baseline_m},
                     {&fp::kFovealMappedBaselineM, &x.mapped_baseline_m},
                     {&fp::kFovealChoosePlacement, &x.choose_placement},
                     {&fp::kFovealLeftPair, &x.left_pair},
                     {&fp::kFovealLeftPairFirst, &x.left_pair_first},
                     {&fp::kFovealMapCheck, &x.map_check},
                     {&fp::kFovealVergenceMaxIterations, &x.vergence.max_iterations},
                     {&fp::kFovealVergenceTolerancePx, &x.vergence.tolerance_px},
                     {&fp::kFovealVergenceMinDistanceM, &x.vergence.min_distance_m},
                     {&fp::kFovealHorizontalDisparityLimitPx,
                      &x.foveal.tessellation.horizontal_disparity_limit_px},
                     {&fp::kFovealMaxLevels, &x.foveal.tessellation.max_levels},
                     {&fp::kFovealMinFoveaPx, &x.foveal.tessellation.min_fovea_px},
                     {&fp::kFovealFoveaPatchPx, &x.foveal.fovea_patch_px},
                     {&fp::kFovealPeripheryPatchPx, &x.foveal.periphery_patch_px},
                     {&fp::kFovealMapMarginPx, &x.foveal.map_margin_px},
                     {&fp::kFovealCoarseMarginPx, &x.foveal.coarse_margin_px},
                     {&fp::kFovealEdgeErosionPx, &x.foveal.edge_erosion_px},
                     {&fp::kFovealFoveaEdgeErosionPx, &x.foveal.fovea_edge_erosion_px},
                     {&fp::kFovealEdgeJumpPx, &x.foveal.edge_jump_px},
                     {&fp::kFovealEdgeHolePx, &x.foveal.edge_hole_px},
                     {&fp::kFovealMinFillShare, &x.foveal.blocks.min_fill_share},
                     {&fp::kFovealMinBlockPx, &x.foveal.blocks.min_block_px},
                     {&fp::kFovealPeripheryMinBlockPx, &x.foveal.periphery_min_block_px},
                     {&fp::kFovealPeripheryHalfAgreement, &x.foveal.periphery_half_agreement},
                     {&fp::kFovealClipToInliers, &x.foveal.blocks.clip_to_inliers},
                     {&fp::kFovealClipDiagonals, &x.foveal.blocks.clip_diagonals},
                     {&fp::kFovealRectify, &x.foveal.rectify},
                     {&fp::kFovealRectifiedPeriphery, &x.foveal.rectified_periphery},
                     {&fp::kFovealRectifiedPeripheryFullResolution,
                      &x.foveal.rectified_periphery_full_resolution},
                     {&fp::kFovealSkipFovealEdgePx, &x.foveal.skip_foveal_edge_px},
                     {&fp::kFovealMaxViewAngleDeg, &x.foveal.max_view_angle_deg},
                     {&fp::kFovealFitMinSupport, &x.foveal.plane_fit.min_support},
                     {&fp::kFovealFitTolerancePx, &x.foveal.plane_fit.fit_tolerance_px},
                     {&fp::kFovealFitMinInlierShare, &x.foveal.plane_fit.min_inlier_share},
                     {&fp::kFovealFitRequireQuadrants, &x.foveal.plane_fit.require_quadrants},
                     {&fp::kFovealSilentCheck, &f.silent_check},
                     {&fp::kFovealServoWindowHalfPx, &x.servo.window_half_px},
                     {&fp::kFovealServoTolerancePx, &x.servo.tolerance_px},
                     {&fp::kFovealServoSearchPx, &x.servo.search_px},
                     {&fp::kFovealServoRefinePx, &x.servo.refine_px},
                     {&fp::kFovealServoUniqueRatio, &x.servo.unique_ratio},
                     {&fp::kFovealServoMutualPx, &x.servo.mutual_tolerance_px},
                     {&fp::kFovealSilentConfidence, &x.foveal.silent_confidence},
                     {&fp::kFovealRectifiedSilentConfidence, &x.foveal.rectified_silent_confidence},
                     {&fp::kFovealSilentCheckLevel, &x.foveal.silent_check_level},
                     {&fp::kFovealSilentOutsideSeed, &x.foveal.silent_outside_seed},
                     {&fp::kFovealServoMaxSteps, &x.servo.max_steps},
                 });
}

// The matchers, selection, criteria, the static baseline, integration.
void AddDdrParams(RunConfig* c, std::vector<ConfigParam>* params) {
  namespace fp = fovea::params;
  namespace ep = params;
  fovea::FoveaOptions& f = c->fovea;
  params->insert(
      params->end(),
      {
          {&fp::kNl1WindowHalfPx, &f.nl1.window_half_px},
          {&fp::kNl1MinTextureDn, &f.nl1.min_texture_dn},
          {&fp::kNl1LrTolerancePx, &f.nl1.lr_tolerance_px},
          {&fp::kNl1WeakWindowHalfPx, &f.nl1.weak_window_half_px},
          {&fp::kNl1WeakTextureDn, &f.nl1.weak_texture_dn},
          {&fp::kNl1Cost, &f.nl1.cost},
          {&fp::kSgbmBlockSize, &f.sgbm.block_size},
          {&fp::kSgbmUniquenessRatio, &f.sgbm.uniqueness_ratio},
          {&fp::kSgbmSpeckleWindow, &f.sgbm.speckle_window},
          {&fp::kSgbmSpeckleRange, &f.sgbm.speckle_range},
          {&fp::kSelectionStrategy, &f.selection.strategy},
          {&fp::kSelectionFirstFixation, &f.selection.first_fixation},
          {&fp::kSelectionView, &f.selection.view},
          {&fp::kSelectionReferenceFallback, &f.selection.reference_fallback},
          {&fp::kSelectionFoveaSizePx, &f.selection.fovea_size_px},
          {&fp::kSelectionMotionWeight, &f.selection.motion_weight},
          {&fp::kSelectionHalfKnownRelSigma, &f.selection.half_known_rel_sigma},
          {&fp::kSelectionDeterministic, &f.selection.deterministic},
          {&fp::kSelectionDrawScale, &f.selection.draw_scale},
          {&fp::kSelectionHistogramBins, &f.selection.histogram_bins},
          {&fp::kSelectionBorderPx, &f.selection.border_px},
          {&fp::kSelectionResolutionLevel, &f.selection.resolution_level},
          {&fp::kSelectionRefusedRadiusM, &f.selection.refused_radius_m},
          {&fp::kCriteriaGradient, &f.criteria.gradient},
          {&fp::kCriteriaSuppression, &f.criteria.suppression},
          {&fp::kCriteriaProximity2d, &f.criteria.proximity_2d},
          {&fp::kCriteriaProximity3d, &f.criteria.proximity_3d},
          {&fp::kCriteriaGradientBlurPx, &f.criteria.gradient_blur_px},
          {&fp::kCriteriaSuppressedWeight, &f.criteria.suppressed_weight},
          {&fp::kCriteriaSuppressionRadiusM, &f.criteria.suppression_radius_m},
          {&fp::kCriteriaPeripheralWeight, &f.criteria.peripheral_weight},
          {&fp::kCriteriaRevisitRadiusM, &f.criteria.revisit_radius_m},
          {&fp::kCriteriaHoleWidthPx, &f.criteria.hole_width_px},
          {&fp::kCriteriaHoleEdgeWeight, &f.criteria.hole_edge_weight},
          {&fp::kCriteriaHoleInsideWeight, &f.criteria.hole_inside_weight},
          {&fp::kCriteriaProximity2dScalePx, &f.criteria.proximity_2d_scale_px},
          {&fp::kCriteriaProximity3dLow, &f.criteria.proximity_3d_low},
          {&ep::kStaticBaselineM, &c->static_baseline_m},
          {&ep::kScoreCompareStatic, &c->compare_static},
          {&fp::kIntegrationOverlapShare, &f.integration.overlap_share},
          {&fp::kIntegrationContradictionShare, &f.integration.contradiction_share},
          {&fp::kIntegrationFuse, &f.integration.fuse},
          {&fp::kIntegrationFuseAcrossLevels, &f.integration.fuse_across_levels},
          {&fp::kIntegrationRetireIdr, &f.integration.retire_idr},
          {&fp::kIntegrationRetireIdrShare, &f.integration.retire_idr_share},
          {&fp::kIntegrationRetireInFixationView, &f.integration.retire_in_fixation_view},
          {&fp::kIntegrationReferenceMinNcc, &f.integration.reference_min_ncc},
          {&fp::kIntegrationReferencePooledMinNcc, &f.integration.reference_pooled_min_ncc},
          {&fp::kIntegrationReferenceSidePx, &f.integration.reference_side_px},
          {&fp::kIntegrationReferenceFlankPx, &f.integration.reference_flank_px},
      });
}

}  // namespace

std::vector<ConfigParam> ConfigParams(RunConfig* c) {
  std::vector<ConfigParam> params;
  params.reserve(128);
  for (auto add :
       {AddTopParams, AddRigParams, AddLoopParams, AddIdrParams, AddFovealParams, AddDdrParams})
    add(c, &params);
  return params;
}

void SetParam(RunConfig* config, const std::string& path, const std::string& value) {
  for (const ConfigParam& p : ConfigParams(config))
    if (p.path() == path) return Assign(p, value, "key '" + path + "'");
  throw UsageError("unknown key '" + rig::ClipForMessage(path) + "'");
}

void SetParams(RunConfig* config, const std::vector<std::string>& key_values) {
  for (const std::string& kv : key_values) {
    const size_t eq = kv.find('=');
    if (eq == std::string::npos)
      throw UsageError("--set expects KEY=VALUE, got '" + rig::ClipForMessage(kv) + "'");
    SetParam(config, kv.substr(0, eq), kv.substr(eq + 1));
  }
}

void SetParamFromFlag(RunConfig* config, const std::string& flag, const std::string& path,
                      const std::string& value) {
  for (const ConfigParam& p : ConfigParams(config))
    if (p.path() == path) return Assign(p, value, flag + " (" + path + ")");
  throw std::logic_error("flag " + flag + " names no parameter '" + path + "'");
}

namespace {
void Walk(const YAML::Node& node, const std::string& prefix,
          std::map<std::string, const ConfigParam*>& params, const std::string& where) {
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    const std::string path = prefix.empty() ? key : prefix + "." + key;
    const auto it = params.find(path);
    if (kv.second.IsMap()) {
      if (it != params.end())
        throw UsageError(where + "key '" + path + "': expected a value, got a mapping");
      bool known_section = false;
      for (const auto& [name, p] : params) known_section |= name.rfind(path + ".", 0) == 0;
      if (!known_section)
        throw UsageError(where + "unknown key '" + rig::ClipForMessage(path) + "'");
      Walk(kv.second, path, params, where);
      continue;
    }
    if (it == params.end())
      throw UsageError(where + "unknown key '" + rig::ClipForMessage(path) + "'");
    if (!kv.second.IsScalar())
      throw UsageError(where + "key '" + path + "': expected a single value");
    Assign(*it->second, kv.second.Scalar(), where + "key '" + path + "'");
  }
}
}  // namespace

namespace {
// yaml-cpp keeps a mapping's repeated keys (the last wins on lookup) and lets
// aliases share nodes: refuse the first, and bound the walk for the second.
void CheckYamlTree(const YAML::Node& node, const std::string& where, long* budget) {
  constexpr long kMaxNodes = 1000000;
  if (++*budget > kMaxNodes)
    throw UsageError(where + "more than " + std::to_string(kMaxNodes) + " values");
  if (node.IsMap()) {
    std::set<std::string> keys;
    for (const auto& kv : node) {
      if (!kv.first.IsScalar()) throw UsageError(where + "a key that is not a single value");
      if (!keys.insert(kv.first.Scalar()).second)
        throw UsageError(where + "key '" + rig::ClipForMessage(kv.first.Scalar()) +
                         "' appears twice");
      CheckYamlTree(kv.second, where, budget);
    }
  } else if (node.IsSequence()) {
    for (const auto& item : node) CheckYamlTree(item, where, budget);
  }
}

// Records where each document of a YAML stream starts (nothing else).
class DocumentStarts : public YAML::EventHandler {
 public:
  std::vector<YAML::Mark> starts;
  void OnDocumentStart(const YAML::Mark& mark) override { starts.push_back(mark); }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
};

}  // namespace

YAML::Node ParseYaml(const std::string& text, const std::string& where) {
  auto invalid = [&](const YAML::Mark& mark, const std::string& why) {
    return UsageError(where + "not valid YAML (line " + std::to_string(mark.line + 1) + ": " +
                      rig::ClipForMessage(why) + ")");
  };
  YAML::Node root;
  try {
    // One document, counted by the parser itself, which stops at the second
    // (yaml-cpp 0.7's LoadAll never ends on a stray ',': its parser does not
    // advance, so a document starting where the last one did is an error).
    std::istringstream in(text);
    YAML::Parser parser(in);
    DocumentStarts documents;
    while (documents.starts.size() < 2 && parser.HandleNextDocument(documents)) {
    }
    if (documents.starts.size() == 2) {
      if (documents.starts[1].pos == documents.starts[0].pos)
        throw invalid(documents.starts[0], "unreadable text");
      throw UsageError(where + "holds more than one YAML document (a second starts at line " +
                       std::to_string(documents.starts[1].line + 1) + "); expected one");
    }
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw invalid(e.mark, e.msg);
  }
  long budget = 0;
  CheckYamlTree(root, where, &budget);
  return root;
}

YAML::Node LoadYamlFile(const std::string& path, const std::string& where) {
  std::string text;
  try {
    text = rig::ReadInputFile(path, "file");
  } catch (const rig::InputError& e) {
    throw UsageError(where + e.what());
  }
  return ParseYaml(text, where);
}

RunConfig LoadConfig(const std::string& path) {
  const std::string where = "config " + rig::ClipForMessage(path) + ": ";
  const YAML::Node root = LoadYamlFile(path, where);
  RunConfig config;
  ApplyYaml(root, &config, where);
  try {
    config.Check();
  } catch (const rig::InputError& e) {
    throw UsageError(where + e.what());
  }
  return config;
}

void ApplyYaml(const YAML::Node& root, RunConfig* config, const std::string& where) {
  if (root.IsNull()) return;
  if (!root.IsMap()) throw UsageError(where + "expected a mapping of keys at the top level");
  const std::vector<ConfigParam> params = ConfigParams(config);
  std::map<std::string, const ConfigParam*> by_path;
  for (const ConfigParam& p : params) by_path[p.path()] = &p;
  Walk(root, "", by_path, where);
}

void RunConfig::Check() const {
  // Each parameter against its spec (the libraries' Check() use the same
  // specs for their own options), then the parts against each other.
  try {
    fovea.Check();
    rig.Check();
    RunConfig copy = *this;
    for (const ConfigParam& p : ConfigParams(&copy)) {
      if (const auto* d = std::get_if<double*>(&p.target)) rig::CheckParam(*p.spec, **d);
      if (const auto* i = std::get_if<int*>(&p.target)) rig::CheckParam(*p.spec, **i);
      if (const auto* u = std::get_if<uint64_t*>(&p.target))
        rig::CheckParam(*p.spec, static_cast<double>(**u));
      if (const auto* t = std::get_if<std::string*>(&p.target)) rig::CheckParam(*p.spec, **t);
    }
  } catch (const UsageError&) {
    throw;
  } catch (const rig::InputError& e) {
    throw UsageError(e.what());
  }
  const auto units = SixInts(hardware.units, "rig.units");
  for (int i = 0; i < 6; ++i) {
    if (units[i] < 1 || units[i] > 99)
      throw UsageError("key 'rig.units': addresses must be 1 to 99");
    for (int j = 0; j < i; ++j)
      if (units[j] == units[i])
        throw UsageError("key 'rig.units': address " + std::to_string(units[i]) + " appears twice");
  }
  for (const int d : SixInts(hardware.directions, "rig.directions"))
    if (d != 1 && d != -1) throw UsageError("key 'rig.directions': each must be 1 or -1");
  if (hardware.type == "hardware") {
    if (hardware.port.empty() && !hardware.emulate_stages)
      throw UsageError(
          "key 'rig.port': a hardware rig needs the stages' serial port (or rig.emulate_stages: "
          "true)");
    if (hardware.left_camera.empty())
      throw UsageError("key 'rig.left_camera': a hardware rig needs a left camera");
    if (hardware.right_camera.empty())
      throw UsageError("key 'rig.right_camera': a hardware rig needs a right camera");
    if (rig.calibration.empty())
      throw UsageError("key 'rig.calibration': a hardware rig needs a calibration file");
  }
  const double widest = 2 * rig.carriage_max_m;
  for (const auto& [key, baseline] :
       {std::pair<const char*, double>{"foveal.baseline_m", fovea.fixation.baseline_m},
        {"foveal.mapped_baseline_m", fovea.fixation.mapped_baseline_m},
        {"static.baseline_m", static_baseline_m}})
    if (baseline > widest)
      throw UsageError(std::string("key '") + key + "': " + FormatNumber(baseline) +
                       " is wider than the carriages allow (2 x rig.carriage_max_m = " +
                       FormatNumber(widest) + ")");
}

std::vector<std::string> SplitFields(const std::string& text) {
  std::vector<std::string> fields;
  size_t start = 0;
  for (size_t comma; (comma = text.find(',', start)) != std::string::npos; start = comma + 1)
    fields.push_back(text.substr(start, comma - start));
  fields.push_back(text.substr(start));
  return fields;
}

std::array<int, 6> SixInts(const std::string& text, const std::string& key) {
  const std::vector<std::string> fields = SplitFields(text);
  std::array<int, 6> v{};
  bool ok = fields.size() == v.size();
  for (size_t i = 0; ok && i < v.size(); ++i) {
    const std::optional<double> x = ParseNumber(fields[i]);
    ok = x && *x == std::floor(*x) && std::abs(*x) <= 1e6;
    v[i] = ok ? static_cast<int>(*x) : 0;
  }
  if (!ok)
    throw UsageError("key '" + key + "': expected six whole numbers separated by commas, got '" +
                     rig::ClipForMessage(text) + "'");
  return v;
}

std::vector<std::pair<std::string, std::string>> ParamValues(const RunConfig& const_config) {
  RunConfig config = const_config;
  std::vector<std::pair<std::string, std::string>> values;
  for (const ConfigParam& p : ConfigParams(&config)) values.emplace_back(p.path(), ValueText(p));
  return values;
}

std::string CanonicalConfig(const RunConfig& config) {
  std::string text;
  for (const auto& [path, value] : ParamValues(config)) text += path + "=" + value + "\n";
  return text;
}

std::string ConfigHash(const RunConfig& config) {
  uint64_t h = 1469598103934665603ull;
  for (const unsigned char ch : CanonicalConfig(config)) {
    h ^= ch;
    h *= 1099511628211ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string ParamText(RunConfig* config, const std::string& path) {
  for (const ConfigParam& p : ConfigParams(config))
    if (p.path() == path) return ValueText(p);
  throw UsageError("unknown key '" + path + "'");
}

std::string DumpConfig(const RunConfig& const_config) {
  RunConfig config = const_config;
  std::ostringstream out;
  out << "# FOVEA run configuration: every parameter, with its meaning and range.\n";
  std::string section;
  for (const ConfigParam& p : ConfigParams(&config)) {
    const std::string path = p.path();
    const size_t dot = path.find('.');
    const std::string sec = dot == std::string::npos ? "" : path.substr(0, dot);
    const std::string key = dot == std::string::npos ? path : path.substr(dot + 1);
    if (sec != section) {
      out << sec << ":\n";
      section = sec;
    }
    const std::string indent = sec.empty() ? "" : "  ";
    out << indent << key << ": " << YamlValueText(p) << "  # " << p.spec->doc << "; " << Range(p)
        << "\n";
  }
  return out.str();
}

}  // namespace experiments
