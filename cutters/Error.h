#pragma once
/// \file Error.h
/// The typed exceptions of engage. Every library throws these; the `engage` application
/// catches them, prints one line and exits non-zero. Libraries report errors only by throwing
/// these; the run layer (engine/run) alone writes to stderr, for progress, warnings and a
/// batch's log lines.

#include <stdexcept>
#include <string>

namespace engage {

/// Base of every error engage reports to a user: the message is complete and printable.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// A parameter out of range or inconsistent with another: names the parameter and its value.
/// Example message: "corner radius r_tc = 7 mm must not exceed the cutter radius r = 6 mm".
class ParameterError : public Error {
 public:
  explicit ParameterError(const std::string& message) : Error(message) {}
};

/// The run was asked to stop (SIGINT, SIGTERM: engage::requestStop in Simulation.h) and
/// unwound: what it had made is removed as after any failure.
class Interrupted : public Error {
 public:
  Interrupted() : Error("interrupted") {}
};

}  // namespace engage
