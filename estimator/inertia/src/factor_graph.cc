#include "internal.h"
namespace tactforce::inertia::internal {
absl::StatusOr<MethodOutput> FitFactorGraph(const InertiaSamples& s, const InertiaOptions& o, const ConvexHull* hull) { return absl::UnimplementedError("fg"); }
}
