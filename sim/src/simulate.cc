// The fingertip simulation: the 42-taxel geometry, GeoDEx IV-A aggregation,
// force profiles (press-release, ramp, random) drawn from a seed, and
// SimulateSensor, which samples the profile on a grid oversampled for exact
// delay and lag, runs every taxel under the contact patch through the sensor
// model's channel (sim::ApplyChannel), adds noise and aggregates the output
// samples; plus the run's CSV/JSON writer (the audit's input format).
#include "tactforce/sim/simulate.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tactforce/io/text_file.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A force profile as a continuous function of time: piecewise phases.
struct Phase {
  double t0, t1;
  double f0, f1;  // force at start/end
  double r0, r1;  // shear ratio at start/end
  bool cosine;    // raised-cosine (smooth) or linear interpolation
};

class ProfileFn {
 public:
  void Add(double dur, double f1, double r1, bool cosine) {
    double t0 = phases_.empty() ? 0 : phases_.back().t1;
    double f0 = phases_.empty() ? 0 : phases_.back().f1;
    double r0 = phases_.empty() ? 0 : phases_.back().r1;
    phases_.push_back({t0, t0 + dur, f0, f1, r0, r1, cosine});
  }
  double end() const { return phases_.empty() ? 0 : phases_.back().t1; }
  void Eval(double t, double* f, double* ratio) const {
    if (phases_.empty()) {
      *f = *ratio = 0;
      return;
    }
    auto it = std::upper_bound(phases_.begin(), phases_.end(), t,
                               [](double v, const Phase& p) { return v < p.t1; });
    if (it == phases_.end()) it = phases_.end() - 1;
    const Phase& p = *it;
    double s = std::clamp((t - p.t0) / (p.t1 - p.t0), 0.0, 1.0);
    if (p.cosine) s = 0.5 - 0.5 * std::cos(kPi * s);
    *f = p.f0 + (p.f1 - p.f0) * s;
    *ratio = p.r0 + (p.r1 - p.r0) * s;
  }

 private:
  std::vector<Phase> phases_;
};

struct RandomFn {
  std::vector<double> amp, freq, phase;
  std::vector<double> ramp, rfreq, rphase;
  double mean = 0, scale = 1, max_ratio = 0.6;
  void Eval(double t, double* f, double* ratio) const {
    double v = mean;
    for (size_t i = 0; i < amp.size(); ++i)
      v += amp[i] * std::sin(2 * kPi * freq[i] * t + phase[i]);
    *f = std::max(0.0, v * scale);
    double r = 0.5;
    for (size_t i = 0; i < ramp.size(); ++i)
      r += ramp[i] * std::sin(2 * kPi * rfreq[i] * t + rphase[i]);
    *ratio = max_ratio * std::clamp(r, 0.0, 1.0);
  }
};

}  // namespace

std::vector<Taxel> DefaultFingertip(const FingertipGeometry& g) {
  std::vector<Taxel> taxels;
  const Eigen::Vector3d centre(0, 0, g.body_length);
  auto sphere = [&](double polar, double az) {
    Eigen::Vector3d n(std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az),
                      std::cos(polar));
    taxels.push_back({centre + g.radius * n, n});
  };
  sphere(0, 0);
  for (int k = 0; k < 6; ++k) sphere(kPi / 6, 2 * kPi * k / 6);
  for (int k = 0; k < 10; ++k) sphere(kPi / 3, 2 * kPi * k / 10 + kPi / 10);
  for (int ring = 0; ring < 5; ++ring) {
    const double z = g.body_length * (ring + 0.5) / 5.0;
    for (int k = 0; k < 5; ++k) {
      const double az = 2 * kPi * k / 5 + (ring % 2) * kPi / 5;
      Eigen::Vector3d n(std::cos(az), std::sin(az), 0);
      taxels.push_back({Eigen::Vector3d(g.radius * n.x(), g.radius * n.y(), z), n});
    }
  }
  return taxels;
}

FingertipReading AggregateFingertip(const std::vector<Taxel>& taxels,
                                    const std::vector<double>& readings) {
  FingertipReading r;
  double wsum = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < taxels.size() && i < readings.size(); ++i) {
    r.force += readings[i];
    const double w = std::max(0.0, readings[i]);
    wsum += w;
    p += w * taxels[i].position;
    n += w * taxels[i].normal;
  }
  if (wsum > 1e-12) {
    r.location = p / wsum;
    if (n.norm() > 1e-12) r.normal = n.normalized();
  }
  return r;
}

absl::StatusOr<Profile> ParseProfile(std::string_view name) {
  if (name == "press-release") return Profile::kPressRelease;
  if (name == "ramp") return Profile::kRamp;
  if (name == "random") return Profile::kRandom;
  return absl::InvalidArgumentError(absl::StrCat("profile: unknown '", std::string(name),
                                                 "' (expected press-release, ramp or random)"));
}

const char* ToString(Profile p) {
  switch (p) {
    case Profile::kPressRelease:
      return "press-release";
    case Profile::kRamp:
      return "ramp";
    case Profile::kRandom:
      return "random";
  }
  return "?";
}

namespace {

// Checks the options against the fingertip's taxel count; InvalidArgument
// naming the option or the model field.
absl::Status ValidateSimOptions(const SensorModel& model, const SimOptions& o, int n_taxels) {
  TF_RETURN_IF_ERROR(ValidateSensorModel(model));
  if (!(o.seconds > 0) || o.seconds > 3600)
    return absl::InvalidArgumentError(
        absl::StrCat("seconds: must be in (0, 3600], got ", o.seconds));
  if (!(o.rate > 0) || o.rate > 100000)
    return absl::InvalidArgumentError(
        absl::StrCat("rate: must be in (0, 100000] Hz, got ", o.rate));
  if (o.seconds * o.rate < 2 || o.seconds * o.rate > 2e7)
    return absl::InvalidArgumentError(
        absl::StrCat("seconds * rate: between 2 and 2e7 samples, got ", o.seconds * o.rate));
  if (!(o.min_peak > 0) || !(o.max_peak >= o.min_peak))
    return absl::InvalidArgumentError("min_peak/max_peak: need 0 < min_peak <= max_peak");
  if (o.oversample < 1 || o.oversample > 64)
    return absl::InvalidArgumentError("oversample: must be in [1, 64]");
  if (o.reference_noise < 0) return absl::InvalidArgumentError("reference_noise: must be >= 0");
  if (o.contact_radius < 0) return absl::InvalidArgumentError("contact_radius: must be >= 0");
  if (o.contact_taxel < 0 || o.contact_taxel >= n_taxels)
    return absl::InvalidArgumentError(
        absl::StrCat("contact_taxel: must be in [0, ", n_taxels - 1, "], got ", o.contact_taxel));
  return absl::OkStatus();
}

double Uniform(std::mt19937_64& rng, double a, double b) {
  return std::uniform_real_distribution<double>(a, b)(rng);
}

// The normal force (N) and shear ratio of a profile as functions of time (s).
struct ForceProfile {
  bool random = false;
  ProfileFn phases;  // press-release and ramp
  RandomFn sines;    // random
  void Eval(double t, double* f, double* ratio) const {
    if (random)
      sines.Eval(t, f, ratio);
    else
      phases.Eval(t, f, ratio);
  }
};

// Presses until `total` s: rest, raised-cosine press to a drawn peak, hold
// (+/-10 % wander), release; the shear ratio drawn per press.
void DrawPressRelease(const SimOptions& o, double total, std::mt19937_64& rng, ProfileFn* pf) {
  pf->Add(Uniform(rng, 0.2, 0.5), 0, 0, false);  // initial rest
  while (pf->end() < total) {
    const double peak = Uniform(rng, o.min_peak, o.max_peak);
    const double ratio = Uniform(rng, 0, o.max_shear_ratio);
    pf->Add(Uniform(rng, 0.15, 0.5), peak, ratio, true);  // press
    // Hold with a slight wander; the wander is drawn before the duration (the
    // order GCC evaluated the arguments of the one-line form in).
    const double hold_force = peak * Uniform(rng, 0.9, 1.1);
    pf->Add(Uniform(rng, 0.1, 0.6), hold_force, ratio, true);
    pf->Add(Uniform(rng, 0.15, 0.5), 0, ratio, true);  // release
    pf->Add(Uniform(rng, 0.2, 0.5), 0, 0, false);      // rest
  }
}

// Linear ramps up and down with short holds until `total` s.
void DrawRamps(const SimOptions& o, double total, std::mt19937_64& rng, ProfileFn* pf) {
  pf->Add(0.5, 0, 0, false);
  while (pf->end() < total) {
    const double peak = Uniform(rng, o.min_peak, o.max_peak);
    const double ratio = Uniform(rng, 0, o.max_shear_ratio);
    pf->Add(Uniform(rng, 1.5, 4.0), peak, ratio, false);
    pf->Add(Uniform(rng, 0.2, 1.0), peak, ratio, false);
    pf->Add(Uniform(rng, 1.5, 4.0), 0, ratio, false);
    pf->Add(Uniform(rng, 0.3, 1.0), 0, 0, false);
  }
}

// Six force sinusoids (0.1-1.5 Hz) clipped at 0, three for the shear ratio.
void DrawSines(const SimOptions& o, std::mt19937_64& rng, RandomFn* rf) {
  for (int i = 0; i < 6; ++i) {
    rf->amp.push_back(Uniform(rng, 0.3, 1.0) / (i + 1));
    rf->freq.push_back(Uniform(rng, 0.1, 1.5));
    rf->phase.push_back(Uniform(rng, 0, 2 * kPi));
  }
  for (int i = 0; i < 3; ++i) {
    rf->ramp.push_back(Uniform(rng, 0.1, 0.3));
    rf->rfreq.push_back(Uniform(rng, 0.05, 0.5));
    rf->rphase.push_back(Uniform(rng, 0, 2 * kPi));
  }
  double asum = 0;
  for (double a : rf->amp) asum += a;
  rf->mean = 0.25 * asum;  // some contact loss: the force is clipped at 0
  rf->scale = 0.5 * (o.min_peak + o.max_peak) / (1.25 * asum) * 1.6;
  rf->max_ratio = o.max_shear_ratio;
}

// The profile of o.profile, drawn from rng, covering the run plus 1 s.
ForceProfile DrawForceProfile(const SimOptions& o, std::mt19937_64& rng) {
  ForceProfile p;
  p.random = o.profile == Profile::kRandom;
  const double total = o.seconds + 1.0;
  if (o.profile == Profile::kPressRelease)
    DrawPressRelease(o, total, rng, &p.phases);
  else if (o.profile == Profile::kRamp)
    DrawRamps(o, total, rng, &p.phases);
  else
    DrawSines(o, rng, &p.sines);
  return p;
}

// The contact patch: each taxel's share of the force (Gaussian over the
// taxels within contact_radius of the contact taxel, summing to 1; all on
// the contact taxel when the radius is 0).
std::vector<double> ContactWeights(const std::vector<Taxel>& taxels, const SimOptions& o) {
  std::vector<double> weight(taxels.size(), 0.0);
  if (o.contact_radius <= 0) {
    weight[o.contact_taxel] = 1;
    return weight;
  }
  const Eigen::Vector3d c = taxels[o.contact_taxel].position;
  double s = 0;
  for (size_t i = 0; i < taxels.size(); ++i) {
    const double d = (taxels[i].position - c).norm();
    if (d <= o.contact_radius)
      weight[i] = std::exp(-0.5 * d * d / (0.25 * o.contact_radius * o.contact_radius));
    s += weight[i];
  }
  for (double& w : weight) w /= s;
  return weight;
}

// The profile on the fine (oversampled) grid, with a 0.5 s lead-in at zero
// force for the delay/lag history: t (s), force and shear (N).
struct FineGrid {
  int lead = 0;   // samples before t = 0
  int n_out = 0;  // output samples
  std::vector<double> t, force, shear;
};

FineGrid SampleFineGrid(const ForceProfile& profile, const SimOptions& o) {
  FineGrid g;
  g.n_out = static_cast<int>(std::floor(o.seconds * o.rate + 1e-9));
  const double h = 1.0 / (o.rate * o.oversample);
  g.lead = static_cast<int>(std::ceil(0.5 / h));
  const int n_fine = g.lead + g.n_out * o.oversample;
  g.t.resize(n_fine);
  g.force.resize(n_fine);
  g.shear.resize(n_fine);
  for (int k = 0; k < n_fine; ++k) {
    g.t[k] = (k - g.lead) * h;
    double f, r;
    profile.Eval(std::max(0.0, g.t[k]), &f, &r);
    if (g.t[k] < 0) f = r = 0;
    g.force[k] = f;
    g.shear[k] = r * f;
  }
  return g;
}

// Channel output (N) on the fine grid of every taxel with a positive weight
// (in taxel order), from its share of force and shear, plus the partial-
// contact error on the partially covered ones. Drift is referenced to t = 0
// of the run (not the lead-in).
std::vector<std::vector<double>> SimulateTaxels(const SensorModel& model, const FineGrid& g,
                                                const std::vector<double>& weight,
                                                const std::vector<int>& active) {
  const int n_fine = static_cast<int>(g.t.size());
  const double wmax = *std::max_element(weight.begin(), weight.end());
  std::vector<std::vector<double>> taxel_out(active.size());
  std::vector<double> fshare(n_fine), sshare(n_fine);
  for (size_t a = 0; a < active.size(); ++a) {
    const double w = weight[active[a]];
    for (int k = 0; k < n_fine; ++k) {
      fshare[k] = w * g.force[k];
      sshare[k] = w * g.shear[k];
    }
    ChannelInput in;
    in.t = g.t.data();
    in.force = fshare.data();
    in.shear = sshare.data();
    in.n = n_fine;
    in.t0 = 0;
    ApplyChannel(model.effects, in, &taxel_out[a]);
    const double coverage = w / wmax;
    if (model.partial_error > 0 && coverage < 1) {
      for (int k = 0; k < n_fine; ++k)
        if (fshare[k] > 0) taxel_out[a][k] += model.partial_error * (1 - coverage);
    }
  }
  return taxel_out;
}

// The output samples (every oversample-th fine sample after the lead-in):
// taxel readings with noise, aggregated to the fingertip, the reading
// (gain, offset) and the reference (with its noise).
void SampleOutputs(const SensorModel& model, const SimOptions& o, const std::vector<Taxel>& taxels,
                   const FineGrid& g, const std::vector<int>& active,
                   const std::vector<std::vector<double>>& taxel_out, std::mt19937_64& rng,
                   SimRun* run) {
  const int n_out = g.n_out;
  run->t.resize(n_out);
  run->reference.resize(n_out);
  run->reading.resize(n_out);
  run->shear.resize(n_out);
  run->true_force.resize(n_out);
  run->fingertip.resize(n_out);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<double> readings(taxels.size(), 0.0);
  for (int i = 0; i < n_out; ++i) {
    const int k = g.lead + i * o.oversample;
    run->t[i] = g.t[k];
    run->true_force[i] = g.force[k];
    run->shear[i] = g.shear[k];
    std::fill(readings.begin(), readings.end(), 0.0);
    for (size_t a = 0; a < active.size(); ++a) {
      double v = taxel_out[a][k];
      if (model.noise > 0) v += model.noise * gauss(rng);
      readings[active[a]] = v;
    }
    run->fingertip[i] = AggregateFingertip(taxels, readings);
    run->reading[i] = model.gain * run->fingertip[i].force + model.offset;
    run->reference[i] = g.force[k] + (o.reference_noise > 0 ? o.reference_noise * gauss(rng) : 0.0);
  }
}

}  // namespace

absl::StatusOr<SimRun> SimulateSensor(const SensorModel& model, const SimOptions& o) {
  const std::vector<Taxel> taxels = DefaultFingertip();
  TF_RETURN_IF_ERROR(ValidateSimOptions(model, o, static_cast<int>(taxels.size())));
  std::mt19937_64 rng(o.seed);
  const ForceProfile profile = DrawForceProfile(o, rng);
  const std::vector<double> weight = ContactWeights(taxels, o);
  std::vector<int> active;
  for (size_t i = 0; i < taxels.size(); ++i)
    if (weight[i] > 0) active.push_back(static_cast<int>(i));
  const FineGrid grid = SampleFineGrid(profile, o);
  const std::vector<std::vector<double>> taxel_out = SimulateTaxels(model, grid, weight, active);
  SimRun run;
  run.model = model;
  run.options = o;
  SampleOutputs(model, o, taxels, grid, active, taxel_out, rng, &run);
  return run;
}

std::string SimRunCsv(const SimRun& run) {
  std::string s = "t,reference,reading,shear,trial\n";
  for (size_t i = 0; i < run.t.size(); ++i)
    absl::StrAppendFormat(&s, "%.6f,%.9g,%.9g,%.9g,%d\n", run.t[i], run.reference[i],
                          run.reading[i], run.shear[i], run.options.trial);
  return s;
}

absl::Status WriteSimRun(const SimRun& run, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    return absl::InternalError(absl::StrCat(dir, ": cannot create directory: ", ec.message()));
  TF_RETURN_IF_ERROR(io::WriteTextFile(dir + "/run.csv", SimRunCsv(run)));
  std::string fingertip = "t,force,px,py,pz,nx,ny,nz\n";
  for (size_t i = 0; i < run.t.size(); ++i) {
    const auto& f = run.fingertip[i];
    absl::StrAppendFormat(&fingertip, "%.6f,%.9g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", run.t[i],
                          f.force, f.location.x(), f.location.y(), f.location.z(), f.normal.x(),
                          f.normal.y(), f.normal.z());
  }
  TF_RETURN_IF_ERROR(io::WriteTextFile(dir + "/fingertip.csv", fingertip));
  SensorModel m = run.model;
  if (m.source.empty()) m.source = "simulated (true model)";
  return SaveSensorModel(m, dir + "/model.json");
}

}  // namespace tactforce::sim
