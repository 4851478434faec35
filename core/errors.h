// Typed errors of the core library. Every precondition failure throws one of these;
// adapters and the server map them to user-facing messages (see server/http/problem.h).
#pragma once

#include <stdexcept>
#include <string>

namespace mdn {

// The mesh violates a precondition (empty, non-finite coordinate, index out of range,
// a face that is not a triangle). Thrown before any work is done.
class InvalidMeshError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// A parameter is outside its documented range or otherwise invalid. field() names it
// exactly as in DenoiseParams (and in the JSON API), e.g. "sigma_theta".
class InvalidParamsError : public std::invalid_argument {
 public:
  InvalidParamsError(std::string field, const std::string& message)
      : std::invalid_argument(message), field_(std::move(field)) {}
  const std::string& field() const noexcept { return field_; }

 private:
  std::string field_;
};

// A linear solve failed (factorisation not positive definite, or no convergence).
class SolverError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The caller's ProgressObserver asked to stop; thrown between iterations.
class CancelledError : public std::runtime_error {
 public:
  CancelledError() : std::runtime_error("denoising was cancelled") {}
};

}  // namespace mdn
