// The grasp experiment's configuration: the names of its enums (CLI and JSON
// spellings) and ValidateGraspConfig, whose errors name the config field.
#include "tactforce/experiment/grasp.h"

#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tactforce/io/enum_names.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {

namespace {

// Enum names (io/enum_names.h); parse errors name the config field.
constexpr io::EnumNameRow<GraspObject> kObjectNames[] = {{GraspObject::kSphere, "sphere"},
                                                         {GraspObject::kWrench, "wrench"},
                                                         {GraspObject::kCylinder, "cylinder"},
                                                         {GraspObject::kCube, "cube"}};
constexpr io::EnumNameRow<Feedback> kFeedbackNames[] = {{Feedback::kRaw, "raw"},
                                                        {Feedback::kEstimated, "estimated"}};
constexpr io::EnumNameRow<Admittance> kAdmittanceNames[] = {{Admittance::kFull, "full"},
                                                            {Admittance::kNormal, "normal"}};
constexpr io::EnumNameRow<SensorArray> kSensorNames[] = {{SensorArray::kTaxel, "taxel"},
                                                         {SensorArray::kChannel, "channel"}};
constexpr io::EnumNameRow<ContactSensing> kContactSensingNames[] = {
    {ContactSensing::kTaxelMean, "mean"},
    {ContactSensing::kSurface, "surface"},
    {ContactSensing::kTrueNormal, "true-normal"},
    {ContactSensing::kTrueLocation, "true-location"},
    {ContactSensing::kTruth, "truth"}};
constexpr io::EnumNameRow<Protocol> kProtocolNames[] = {{Protocol::kShort, "short"},
                                                        {Protocol::kPaper, "paper"}};

}  // namespace

const char* ToString(GraspObject o) { return io::EnumName(kObjectNames, o); }

absl::StatusOr<GraspObject> ParseGraspObject(std::string_view name) {
  return io::ParseEnumName(kObjectNames, name, "object");
}

std::vector<GraspObject> AllGraspObjects() {
  return {GraspObject::kSphere, GraspObject::kWrench, GraspObject::kCylinder, GraspObject::kCube};
}

const char* ToString(Feedback f) { return io::EnumName(kFeedbackNames, f); }

absl::StatusOr<Feedback> ParseFeedback(std::string_view name) {
  return io::ParseEnumName(kFeedbackNames, name, "feedback");
}

const char* ToString(Admittance a) { return io::EnumName(kAdmittanceNames, a); }

absl::StatusOr<Admittance> ParseAdmittance(std::string_view name) {
  return io::ParseEnumName(kAdmittanceNames, name, "admittance");
}

const char* ToString(SensorArray s) { return io::EnumName(kSensorNames, s); }

absl::StatusOr<SensorArray> ParseSensorArray(std::string_view name) {
  return io::ParseEnumName(kSensorNames, name, "sensors");
}

const char* ToString(ContactSensing s) { return io::EnumName(kContactSensingNames, s); }

absl::StatusOr<ContactSensing> ParseContactSensing(std::string_view name) {
  return io::ParseEnumName(kContactSensingNames, name, "contact_sensing");
}

const char* ToString(Protocol p) { return io::EnumName(kProtocolNames, p); }

absl::StatusOr<Protocol> ParseProtocol(std::string_view name) {
  return io::ParseEnumName(kProtocolNames, name, "protocol");
}

PhaseDurations ProtocolPhases(Protocol p) {
  if (p == Protocol::kShort) return PhaseDurations{};
  // GeoDEx Fig. 12: converged within 5 s, held to 27 s, lifted, placed back
  // at 33 s, switched to the other feedback at 40 s.
  PhaseDurations d;
  d.close = 0.3;
  d.settle = 5.0;
  d.hold = 21.7;
  d.lift = 1.0;
  d.hold_lifted = 4.0;
  d.place = 1.0;
  d.placed = 7.0;
  d.switched = 10.0;
  return d;
}

const char* ToString(FailureCause c) {
  switch (c) {
    case FailureCause::kNone:
      return "none";
    case FailureCause::kNonActivation:
      return "non_activation";
    case FailureCause::kPhantomForce:
      return "phantom_force";
    case FailureCause::kOverReadingTilt:
      return "over_reading_tilt";
    case FailureCause::kSlipDrop:
      return "slip_drop";
  }
  return "?";
}

std::vector<FailureCause> AllFailureCauses() {
  return {FailureCause::kNonActivation, FailureCause::kPhantomForce, FailureCause::kOverReadingTilt,
          FailureCause::kSlipDrop};
}

const char* ToString(Phase p) {
  switch (p) {
    case Phase::kClose:
      return "close";
    case Phase::kSettle:
      return "settle";
    case Phase::kHold:
      return "hold";
    case Phase::kLift:
      return "lift";
    case Phase::kHoldLifted:
      return "hold";
    case Phase::kPlace:
      return "place";
    case Phase::kPlaced:
      return "placed";
    case Phase::kSwitched:
      return "switched";
  }
  return "?";
}

namespace {

absl::Status ValidateFault(const SensorFault& f) {
  if (f.kind == SensorFault::Kind::kNone) return absl::OkStatus();
  if (f.finger < 0)
    return absl::InvalidArgumentError(
        absl::StrFormat("fault.finger: must be >= 0, got %d", f.finger));
  if (!std::isfinite(f.magnitude))
    return absl::InvalidArgumentError(
        absl::StrFormat("fault.magnitude: must be finite, got %g", f.magnitude));
  if (!(f.start >= 0 && std::isfinite(f.start)))
    return absl::InvalidArgumentError(
        absl::StrFormat("fault.start: must be >= 0, got %g", f.start));
  return absl::OkStatus();
}

}  // namespace

absl::Status ValidateGraspConfig(const GraspConfig& c) {
  auto bad = [](const std::string& field, const std::string& why) {
    return absl::InvalidArgumentError(absl::StrCat(field, ": ", why));
  };
  auto positive = [&](const char* field, double v) -> absl::Status {
    if (!(v > 0 && std::isfinite(v))) return bad(field, absl::StrFormat("must be > 0, got %g", v));
    return absl::OkStatus();
  };
  const PhaseDurations& p = c.phases;
  for (auto [name, v] : {std::pair{"phases.close", p.close},
                         {"phases.settle", p.settle},
                         {"phases.hold", p.hold},
                         {"phases.lift", p.lift},
                         {"phases.hold_lifted", p.hold_lifted}}) {
    TF_RETURN_IF_ERROR(positive(name, v));
  }
  for (auto [name, v] : {std::pair{"phases.place", p.place},
                         {"phases.placed", p.placed},
                         {"phases.switched", p.switched}})
    if (!(v >= 0 && std::isfinite(v))) return bad(name, absl::StrFormat("must be >= 0, got %g", v));
  if (!(c.lift_height >= 0 && c.lift_height <= 0.5))
    return bad("lift_height", absl::StrFormat("must be in [0, 0.5] m, got %g", c.lift_height));
  if (!(c.pivot_angle_deg >= 0 && c.pivot_angle_deg <= 40))
    return bad("pivot_angle_deg", absl::StrFormat("must be in [0, 40], got %g", c.pivot_angle_deg));
  TF_RETURN_IF_ERROR(positive("control_rate", c.control_rate));
  TF_RETURN_IF_ERROR(ValidatePhysics(c.physics));
  if (c.control_rate * c.physics.timestep > 1.0 + 1e-9)
    return bad("control_rate", absl::StrFormat("%g Hz is faster than the physics (timestep %g s)",
                                               c.control_rate, c.physics.timestep));
  if (!(std::isfinite(c.normal_uncertainty_deg) && c.normal_uncertainty_deg < 90))
    return bad("normal_uncertainty_deg",
               absl::StrFormat("must be < 90 deg (negative: from the taxel layout), got %g",
                               c.normal_uncertainty_deg));
  if (!(c.admittance_gain > 0 && c.admittance_gain <= 1))
    return bad("admittance_gain", absl::StrFormat("must be in (0, 1], got %g", c.admittance_gain));
  TF_RETURN_IF_ERROR(positive("kp", c.kp));
  TF_RETURN_IF_ERROR(positive("damping_ratio", c.damping_ratio));
  TF_RETURN_IF_ERROR(positive("fingertip_mass", c.fingertip_mass));
  if (std::sqrt(c.kp / c.fingertip_mass) * c.physics.timestep > 1.0)
    return bad("kp",
               absl::StrFormat(
                   "too stiff for fingertip_mass %g kg at timestep %g s (sqrt(kp/m) dt = %.2f > 1: "
                   "the explicit PD would be unstable)",
                   c.fingertip_mass, c.physics.timestep,
                   std::sqrt(c.kp / c.fingertip_mass) * c.physics.timestep));
  if (!(c.fingertip_radius >= 0.003 && c.fingertip_radius <= 0.03))
    return bad("fingertip_radius",
               absl::StrFormat("must be in [0.003, 0.03] m, got %g", c.fingertip_radius));
  if (!(c.confidence >= 0 && std::isfinite(c.confidence)))
    return bad("confidence", absl::StrFormat("must be >= 0, got %g", c.confidence));
  TF_RETURN_IF_ERROR(positive("max_rotation_deg", c.max_rotation_deg));
  TF_RETURN_IF_ERROR(positive("max_slip", c.max_slip));
  if (!(c.drop_distance > c.max_slip))
    return bad("drop_distance",
               absl::StrFormat("must exceed max_slip (%g m), got %g", c.max_slip, c.drop_distance));
  if (c.sensors == SensorMode::kGeoDexRandom) {
    TF_RETURN_IF_ERROR(ValidateErrorRanges(c.error_ranges, "error_ranges."));
  }
  if (c.sensor_array == SensorArray::kTaxel) {
    TF_RETURN_IF_ERROR(sim::ValidateTaxelRanges(c.taxel_ranges, "taxel_ranges."));
  }
  if (!(c.contact_cap_deg >= 0 && c.contact_cap_deg <= 90))
    return bad("contact_cap_deg",
               absl::StrFormat("must be in [0, 90] deg, got %g", c.contact_cap_deg));
  TF_RETURN_IF_ERROR(ValidateFault(c.fault));
  if (c.sensors == SensorMode::kModel) {
    TF_RETURN_IF_ERROR(
        io::PrependPath(sim::ValidateSensorModel(c.sensor_model), "sensor_model", "."));
    if (c.sensor_model.gain == 0) return bad("sensor_model.gain", "must not be 0");
  }
  return absl::OkStatus();
}

}  // namespace tactforce::experiment
