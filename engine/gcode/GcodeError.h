#pragma once
/// \file GcodeError.h
/// The error of a program that cannot be interpreted: "file:line:col: expected ..., found ...".

#include "cutters/Error.h"

#include <string>

namespace engage {

/// A G-code program error pointing at its source. what() is the complete message.
class GcodeError : public Error {
 public:
  GcodeError(const std::string& file, int line, int column, const std::string& message)
      : Error(file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " + message),
        file_(file),
        line_(line),
        column_(column),
        message_(message) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  int column() const { return column_; }
  /// The message without its "file:line:col: " prefix.
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  int line_;
  int column_;
  std::string message_;
};

}  // namespace engage
