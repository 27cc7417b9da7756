// Early-return helpers for absl::Status / absl::StatusOr, after Abseil's
// status_macros.h (not shipped by Debian 12's Abseil), and the one way to
// prefix a field path onto an error.
#pragma once

#include "absl/strings/string_view.h"
#include <utility>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

// Evaluates `expr` (an absl::Status) once; returns it from the enclosing
// function when it is not OK.
#define TF_RETURN_IF_ERROR(expr)                                \
  do {                                                          \
    if (::absl::Status tf_status_ = (expr); !tf_status_.ok()) { \
      return tf_status_;                                        \
    }                                                           \
  } while (false)

#define TF_STATUS_CONCAT_INNER_(a, b) a##b
#define TF_STATUS_CONCAT_(a, b) TF_STATUS_CONCAT_INNER_(a, b)

// `lhs` is a declaration (`auto x`, `const Foo& y` is not allowed: a value
// or `auto`) or an existing variable. Evaluates `rexpr` (an
// absl::StatusOr<T>) once; returns its status when not OK, else moves the
// value into `lhs`.
#define TF_ASSIGN_OR_RETURN(lhs, rexpr) \
  TF_ASSIGN_OR_RETURN_IMPL_(TF_STATUS_CONCAT_(tf_statusor_, __LINE__), lhs, rexpr)

#define TF_ASSIGN_OR_RETURN_IMPL_(statusor, lhs, rexpr)    \
  auto statusor = (rexpr);                                 \
  if (!statusor.ok()) return std::move(statusor).status(); \
  lhs = *std::move(statusor)

namespace tactforce::io {

// `status` with `path` and `separator` in front of its message (code and
// payloads kept); an OK status, or an empty path, is returned unchanged.
// Nested calls prepend outermost first: PrependPath(PrependPath(s, "mass"),
// "object") reads "object: mass: ...". Separator "." continues a message
// that starts with a field path into a dotted one: PrependPath(s, "plan",
// ".") on "contacts[1].normal: zero length" reads
// "plan.contacts[1].normal: zero length".
absl::Status PrependPath(const absl::Status& status, absl::string_view path,
                         absl::string_view separator = ": ");

}  // namespace tactforce::io
