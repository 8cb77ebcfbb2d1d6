#pragma once
/// \file JsonFile.h
/// JSON files users write (batch manifests, machine descriptions), read strictly.

#include <nlohmann/json.hpp>

#include <string>

namespace engage {

/// The file's JSON. Throws Error naming the file when it cannot be read, is not valid JSON
/// (numbers beyond a double, 9e9999, included), or gives a key twice in one object (which
/// would silently keep only one of its values).
nlohmann::json readJsonFile(const std::string& path);

}  // namespace engage
