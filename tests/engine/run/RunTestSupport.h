#pragma once
// Helpers of the engine/run tests: a fresh folder per test and small programs written into it.

#include <filesystem>
#include <fstream>
#include <string>

namespace engage::test {

/// A new empty folder under the system's temporary folder, removed when the object goes.
class TempFolder {
 public:
  explicit TempFolder(const std::string& name)
      : path_(std::filesystem::temp_directory_path() / ("engage_test_" + name)) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }
  /// Write `text` into the file `name` of the folder; returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    const std::filesystem::path p = path_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }

 private:
  std::filesystem::path path_;
};

/// A plunge to 2 mm at X0 Y0, then a 30 mm slot along +X at 600 mm/min, then a retract: with
/// a 6 mm flat end mill the steady MRR is D d F = 6 * 2 * 600 = 7200 mm^3/min, and the whole
/// slot is 2 mm deep over the stadium of area 30 * 6 + pi 3^2 mm^2.
inline const char* slotProgram() {
  return "G21 G90 G17\nG0 X0 Y0 Z5\nG1 Z-2 F100\nG1 X30 F600\nG0 Z5\nM2\n";
}

}  // namespace engage::test
