// The plan table for people (table.h): fixed-width columns, "-" for absent values.
#include "tactforce/api/table.h"

#include <algorithm>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace tactforce::api {
namespace {

constexpr int kNumberWidth = 11;

// A right-aligned number, or "-" when the response has none.
std::string Cell(bool present, double value) {
  if (!present) return absl::StrFormat("%*s", kNumberWidth, "-");
  return absl::StrFormat("%*.5f", kNumberWidth, value);
}

std::string ContactName(const v1::PlanRequest& request, int i) {
  if (i < request.contacts_size() && !request.contacts(i).name().empty()) {
    return request.contacts(i).name();
  }
  return absl::StrCat("#", i);
}

}  // namespace

std::string FormatPlanTable(const v1::PlanRequest& request, const v1::PlanResponse& response) {
  std::string out;
  absl::StrAppendFormat(&out, "status:      %s\n", StatusName(response.status()));
  if (!response.message().empty()) {
    absl::StrAppendFormat(&out, "message:     %s\n", response.message());
  }

  const int rows = std::max({request.contacts_size(), response.forces_size(),
                             response.normal_forces_size(), response.normal_force_sigma_size()});
  if (rows > 0) {
    int name_width = 7;  // "contact"
    for (int i = 0; i < rows; ++i) {
      name_width = std::max<int>(name_width, ContactName(request, i).size());
    }
    out += "\n";
    absl::StrAppendFormat(&out, "%-*s %*s %*s %*s %*s %*s\n", name_width, "contact", kNumberWidth,
                          "fx [N]", kNumberWidth, "fy [N]", kNumberWidth, "fz [N]", kNumberWidth,
                          "normal [N]", kNumberWidth, "sigma [N]");
    for (int i = 0; i < rows; ++i) {
      const bool has_force = i < response.forces_size();
      const v1::Vec3 f = has_force ? response.forces(i) : v1::Vec3();
      absl::StrAppendFormat(
          &out, "%-*s %s %s %s %s %s\n", name_width, ContactName(request, i),
          Cell(has_force, f.x()), Cell(has_force, f.y()), Cell(has_force, f.z()),
          Cell(i < response.normal_forces_size(),
               i < response.normal_forces_size() ? response.normal_forces(i) : 0.0),
          Cell(i < response.normal_force_sigma_size(),
               i < response.normal_force_sigma_size() ? response.normal_force_sigma(i) : 0.0));
    }
    out += "\n";
  }

  if (response.status() ==
      v1::PLAN_STATUS_OPTIMAL) {  // other answers carry no forces, so no objective
    absl::StrAppendFormat(&out, "objective:   %.6g N^2\n", response.objective());
    absl::StrAppendFormat(&out, "min margin:  %.6g N\n", response.min_margin());
  }
  absl::StrAppendFormat(&out, "solver:      %s\n", SolverName(response.solver()));
  absl::StrAppendFormat(&out, "time:        %d us\n", response.solve_time_us());
  absl::StrAppendFormat(&out, "iterations:  %d\n", response.iterations());
  if (response.has_cross_check()) {
    const v1::CrossCheck& cc = response.cross_check();
    absl::StrAppendFormat(
        &out,
        "cross-check: %s (max |df| %.3g N, objective rel. diff %.3g; geometric %d us, "
        "ipopt %d us, ipopt status %s)\n",
        cc.agree() ? "agree" : "DISAGREE", cc.max_force_diff(), cc.objective_rel_diff(),
        cc.geometric_time_us(), cc.ipopt_time_us(), StatusName(cc.ipopt_status()));
  }
  return out;
}

}  // namespace tactforce::api
