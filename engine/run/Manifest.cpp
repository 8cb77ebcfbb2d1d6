#include "engine/run/Manifest.h"

#include "engine/physics/Material.h"

#include "cutters/Error.h"
#include "engine/run/JsonFile.h"
#include "engine/run/Output.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace engage {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string text(const json& v) {
  return v.is_string() ? v.get<std::string>() : v.dump();
}

/// Check one key of a job's merged spec against the option table; false when the key is a
/// schedule option inherited from the defaults by a simulate job (it does not concern it).
bool checkKey(const std::string& key, const json& value, JobCommand command, const json& own,
              const std::string& where) {
  const OptionInfo* o = findJobOption(key);
  if (!o) throw Error(where + ": unknown option \"" + key + "\"");
  if (o->commandLineOnly)
    throw Error(where + ": \"" + key +
                "\" is not a job option (the batch sets each job's folder and shows progress)");
  if (!appliesTo(*o, command)) {
    if (own.contains(key)) throw Error(where + ": \"" + key + "\" applies to schedule jobs only");
    return false;
  }
  if (!value.is_string() && !value.is_number() && !value.is_boolean())
    throw Error(where + ": \"" + key + "\" must be a string, a number or true/false");
  return true;
}

/// FNV-1a (64 bits), continued over `n` bytes.
std::uint64_t fnv1a(std::uint64_t h, const char* bytes, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(bytes[i]);
    h *= 1099511628211ull;
  }
  return h;
}
constexpr std::uint64_t kFnvStart = 1469598103934665603ull;

std::string hex(std::uint64_t h) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
  return text;
}

/// FNV-1a (64 bits) of a file's bytes as hex, or "unreadable".
std::string contentHash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "unreadable";
  std::uint64_t h = kFnvStart;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0)
    h = fnv1a(h, buf, static_cast<std::size_t>(in.gcount()));
  return hex(h);
}

/// The options that name files: relative to the manifest, and their content part of the job
/// (a FreeCAD .fctl's bits are not: an edited bit alone does not re-run its jobs).
constexpr const char* kFileKeys[] = {"program",  "stock",   "tool-table", "tools",
                                     "material", "machine", "part"};

/// A value of `key` that is not a file: a stock box, a bundled material's name.
bool notAFile(const std::string& key, const std::string& v) {
  if (key == "stock") return v.rfind("box:", 0) == 0 || v.rfind(kStockFromJob, 0) == 0;
  if (key == "material") return !materialIsFile(v);
  return false;
}

/// One job of the manifest, checked and with its files resolved against `base`.
ManifestJob readJob(const json& j, const json& defaults, std::size_t i, const fs::path& base,
                    const std::string& where, std::map<std::string, std::string>& hashes) {
  if (!j.is_object()) throw Error(where + ": expected an object");
  json spec = defaults;
  spec.update(j);
  if (!spec.contains("program")) throw Error(where + ": no \"program\"");
  const std::string command = spec.value("command", "simulate");
  if (command != "simulate" && command != "schedule")
    throw Error(where + ": \"command\" must be simulate or schedule, found \"" + command + "\"");
  spec["command"] = command;
  ManifestJob job;
  job.index = i;
  job.command = command == "schedule" ? JobCommand::Schedule : JobCommand::Simulate;
  // Relative files are relative to the manifest.
  auto resolve = [&](const char* key) {
    if (!spec.contains(key)) return;
    const std::string v = text(spec[key]);
    if (notAFile(key, v)) return;
    if (fs::path(v).is_relative()) spec[key] = (base / v).lexically_normal().string();
  };
  for (const char* key : kFileKeys)
    resolve(key);
  for (const auto& [key, value] : spec.items()) {
    if (key == "name" || key == "command") continue;
    if (key == "program" || checkKey(key, value, job.command, j, where))
      job.values[key] = text(value);
  }
  job.name =
      spec.contains("name") ? text(spec["name"]) : fs::path(text(spec["program"])).stem().string();
  if (job.name.empty() || job.name.find_first_of("/\\") != std::string::npos || job.name == "." ||
      job.name == "..")
    throw Error(where + ": bad job name \"" + job.name + "\"");
  spec["name"] = job.name;
  // The job is its options and the content of its files: an edited program, stock mesh or
  // tool table runs again, an unchanged one is not run twice.
  json content = json::object();
  for (const char* key : kFileKeys) {
    if (!job.values.count(key) ||
        (std::string(key) == "stock" && notAFile(key, job.values.at(key))))
      continue;
    // Many jobs of a large batch share one program: each file is read and hashed once. A
    // bundled material by its file.
    const std::string file =
        std::string(key) == "material" ? materialFile(job.values.at(key)) : job.values.at(key);
    auto it = hashes.find(file);
    if (it == hashes.end()) it = hashes.emplace(file, contentHash(file)).first;
    content[key] = it->second;
  }
  spec["content"] = content;
  job.specJson = spec.dump();
  return job;
}

}  // namespace

std::vector<ManifestJob> readManifest(const std::string& manifest) {
  const fs::path path(manifest);
  json m = readJsonFile(path.string());
  if (!m.is_object() || !m.contains("jobs") || !m["jobs"].is_array())
    throw Error(path.string() + ": expected an object with a \"jobs\" array");
  const json defaults = m.value("defaults", json::object());
  if (!defaults.is_object()) throw Error(path.string() + ": \"defaults\" must be an object");
  for (const auto& [key, value] : m.items())
    if (key != "jobs" && key != "defaults")
      throw Error(path.string() + ": unknown key \"" + key + "\" (expected jobs, defaults)");
  // Files resolve against the manifest's real folder, so that the jobs (and their records)
  // are the same however the manifest's path was typed: relative, absolute, through a link.
  std::error_code ec;
  const fs::path real = fs::weakly_canonical(fs::absolute(path), ec);
  const fs::path base = (ec ? fs::absolute(path) : real).parent_path();
  std::vector<ManifestJob> jobs;
  std::map<std::string, std::string> hashes;  // file -> its content hash
  std::map<std::string, std::size_t> names;
  for (std::size_t i = 0; i < m["jobs"].size(); ++i) {
    const std::string where = path.string() + ": job " + std::to_string(i + 1);
    ManifestJob job = readJob(m["jobs"][i], defaults, i, base, where, hashes);
    if (names.count(job.name))
      throw Error(where + ": the name \"" + job.name + "\" is taken by job " +
                  std::to_string(names[job.name] + 1) + "; give the jobs distinct \"name\"s");
    job.group = i;
    const auto stock = job.values.find("stock");
    if (stock != job.values.end() && stock->second.rfind(kStockFromJob, 0) == 0) {
      // The final stock of an earlier job: this job is that job's chain, and it is that job
      // and its own options (the stock's content is not there before the earlier job runs).
      const std::string from = stock->second.substr(std::string(kStockFromJob).size());
      const auto up = names.find(from);
      if (up == names.end())
        throw Error(where + ": \"stock\": \"" + stock->second +
                    "\" names no earlier job (a job's stock can be the final stock of a job "
                    "before it in the manifest)");
      ManifestJob& source = jobs[up->second];
      source.feedsStock = true;
      job.stockFrom = from;
      job.group = source.group;
      job.depth = source.depth + 1;
      json spec = json::parse(job.specJson);
      spec["content"]["stock"] =
          hex(fnv1a(kFnvStart, source.specJson.data(), source.specJson.size()));
      job.specJson = spec.dump();
    }
    names[job.name] = i;
    jobs.push_back(std::move(job));
  }
  if (jobs.empty()) throw Error(path.string() + ": no jobs");
  return jobs;
}

}  // namespace engage
