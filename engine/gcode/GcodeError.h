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
        column_(column) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  int column() const { return column_; }

 private:
  std::string file_;
  int line_;
  int column_;
};

}  // namespace engage
