// Tests of engine/physics/Material.h: the bundled materials and what a bad file is told.

#include "engine/physics/Material.h"

#include "cutters/Error.h"

#include <catch2/catch.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>

using namespace engage;

namespace {

std::string errorOf(const std::string& text, const std::string& model = "") {
  const std::string path =
      (std::filesystem::temp_directory_path() / "engage_material_test.json").string();
  std::ofstream(path) << text;
  try {
    readMaterial(path, model);
  } catch (const ParameterError& e) {
    std::remove(path.c_str());
    return e.what();
  }
  std::remove(path.c_str());
  return "";
}

}  // namespace

TEST_CASE("the bundled materials read, each with its source", "[physics]") {
  const std::vector<std::string> names = bundledMaterials();
  REQUIRE(names ==
          std::vector<std::string>{"aluminium-7075-t6", "stainless-304", "steel-c45", "ti-6al-4v"});
  for (const std::string& name : names) {
    CAPTURE(name);
    const Material m = readMaterial(name);
    CHECK_FALSE(m.source.empty());
    CHECK_FALSE(m.conditions.empty());
    CHECK_FALSE(m.name.empty());
  }
  // The aluminium has both models: linear by the file's choice, Kienzle on request.
  const Material al = readMaterial("aluminium-7075-t6");
  CHECK(al.model == ForceModel::Linear);
  CHECK(al.linear.Ktc == 767.01);
  CHECK(al.exponent() == 1.0);
  const Material alK = readMaterial("aluminium-7075-t6", "kienzle");
  CHECK(alK.model == ForceModel::Kienzle);
  CHECK(alK.kienzle.kc11 == 800.0);
  CHECK(alK.exponent() == Approx(0.75));
  CHECK(readMaterial("steel-c45").kienzle.kc11 == 1500.0);
}

TEST_CASE("a bad material file or name is an error naming the file and the field", "[physics]") {
  CHECK_THAT(errorOf("{\"linear\": {\"Ktc\": 700, \"Krc\": 100}}"),
             Catch::Contains("\"linear.source\" is missing"));
  CHECK_THAT(errorOf("{\"linear\": {\"Ktc\": 700, \"source\": \"x\"}}"),
             Catch::Contains("\"linear\" needs \"Krc\""));
  CHECK_THAT(errorOf("{\"linear\": {\"Ktc\": -1, \"Krc\": 1, \"source\": \"x\"}}"),
             Catch::Contains("\"linear.Ktc\" must be positive"));
  CHECK_THAT(errorOf("{\"linear\": {\"Ktc\": \"700\", \"Krc\": 1, \"source\": \"x\"}}"),
             Catch::Contains("\"linear.Ktc\" must be a number, found \"700\""));
  CHECK_THAT(errorOf("{\"kienzle\": {\"kc11\": 1500, \"mc\": 1.2, \"source\": \"x\"}}"),
             Catch::Contains("\"kienzle.mc\" must be in [0, 1)"));
  CHECK_THAT(errorOf("{\"kienzle\": {\"kc11\": 1500, \"mc\": 0.2, \"source\": \"x\"}}", "linear"),
             Catch::Contains("has no \"linear\" coefficients (it has \"kienzle\")"));
  CHECK_THAT(errorOf("{\"linear\": "), Catch::Contains("not a material file (JSON)"));
  CHECK_THAT(errorOf("[1, 2]"), Catch::Contains("a material file is a JSON object"));
  std::string unknown;
  try {
    readMaterial("unobtainium");
  } catch (const ParameterError& e) {
    unknown = e.what();
  }
  CHECK_THAT(unknown, Catch::Contains("no material named 'unobtainium'") &&
                          Catch::Contains("aluminium-7075-t6, stainless-304, steel-c45"));
}
