// The parameter space of the audit's candidate effects (not installed): which
// sensor-model fields each effect owns (a Slot each), their bounds and
// coarse start grids, scaled by the measured run; the functional forms of the
// two-form effects; and how a fitted effect is counted (BIC) and reported.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "tactforce/audit/audit.h"
#include "tactforce/audit/measured_data.h"
#include "tactforce/sim/sensor_model.h"

namespace tactforce::audit::internal {

// Facts about the measured run that the parameter bounds scale with.
struct RunStats {
  double fmin, fmax, range, fabsmax;  // reference force, N (range = fmax - fmin)
  double duration;                    // s, last minus first sample time
  double dt;                          // s, median time step (1 when there is none)
  bool has_shear;
};
RunStats ComputeRunStats(const MeasuredData& data);

// One fitted sensor-model field: a double member of EffectParams, or (for a
// Prandtl-Ishlinskii weight) an element of pi_weights.
struct Slot {
  std::string field;
  double sim::EffectParams::*ptr;  // null for a Prandtl-Ishlinskii weight
  double lo, hi;                   // bounds, in the field's units
  std::vector<double> grid;        // coarse start values (sorted)
  int pi_index = -1;               // >= 0: pi_weights[pi_index]
};
double Get(const sim::EffectParams& p, const Slot& s);
void Set(sim::EffectParams& p, const Slot& s, double v);

// The functional form of an effect (hysteresis and nonlinearity have two).
enum class Form { kOnly, kPlay, kPrandtlIshlinskii, kQuadratic, kPowerLaw };
const char* FormName(Form f);  // "" for kOnly, else the report's "form" value
Form DefaultForm(Effect e);    // play for hysteresis, quadratic for nonlinearity
Form FormOf(Effect e, const sim::EffectParams& p);  // the form e has in p

// n values from a to b, evenly spaced on a log scale / a linear scale.
std::vector<double> GeometricGrid(double a, double b, int n);
std::vector<double> LinearGrid(double a, double b, int n);

// Effects whose RSS is smooth in their parameters (refined with LN_BOBYQA).
bool IsSmooth(Effect e);

// The slots of effect e in form `form`; a Prandtl-Ishlinskii hysteresis has
// one slot per weight in *p (none without p).
std::vector<Slot> SlotsFor(Effect e, const RunStats& s, const AuditOptions& o,
                           Form form = Form::kOnly, const sim::EffectParams* p = nullptr);
// Slots of the effects `selected`, each in its form in p. When smooth is
// given, *smooth stays true only while every one of them is smooth.
std::vector<Slot> SelectedSlots(const std::vector<Effect>& selected, const sim::EffectParams& p,
                                const RunStats& st, const AuditOptions& o, bool* smooth);

// Parameters an effect adds to the model (BIC's k): a PI hysteresis counts
// one per active play operator.
int NumParams(Effect e, const sim::EffectParams& p);
// Held-out BIC: n ln(rss / n) + k ln(n).
double Bic(double rss, int n, int k);

// Divides the weights by their sum (when it is positive).
void NormaliseWeights(std::vector<double>* weights);

// Report values of effect e in p: the scalar fields (PI: loop_width and
// operators), and the arrays (PI: pi_thresholds, normalised pi_weights).
std::map<std::string, double> ParamsOf(Effect e, const sim::EffectParams& p, const RunStats& st,
                                       const AuditOptions& o);
std::map<std::string, std::vector<double>> ArrayParamsOf(Effect e, const sim::EffectParams& p);

}  // namespace tactforce::audit::internal
