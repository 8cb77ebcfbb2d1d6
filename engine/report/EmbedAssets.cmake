# Writes a C++ source file that holds text files (the reports' JavaScript and CSS) as string
# literals, for engine/report/ReportAssets.h. Run at build time:
#   cmake -DOUT=ReportAssets.cpp -DNAMES="a.js;b.css" -DFILES="/path/a.js;/path/b.css" -P EmbedAssets.cmake
# Each file goes in as raw string literals of at most 16000 bytes (ISO C++ asks compilers for
# 65536 at least, and -Wpedantic warns above that), joined when first asked for.
list(LENGTH NAMES count)
math(EXPR last "${count} - 1")
set(body "")
set(table "")
foreach(i RANGE ${last})
  list(GET NAMES ${i} name)
  list(GET FILES ${i} path)
  file(READ "${path}" content)
  string(FIND "${content}" ")engage_asset\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "${path} holds the literal's delimiter")
  endif()
  string(LENGTH "${content}" size)
  set(chunks "")
  set(pos 0)
  while(pos LESS size)
    string(SUBSTRING "${content}" ${pos} 16000 piece)
    string(APPEND chunks "    R\"engage_asset(${piece})engage_asset\",\n")
    math(EXPR pos "${pos} + 16000")
  endwhile()
  string(APPEND body "const char* const kAsset${i}[] = {\n${chunks}    nullptr};\n")
  string(APPEND table "    {\"${name}\", kAsset${i}},\n")
endforeach()
file(WRITE "${OUT}.part"
"// Generated from ${FILES} by engine/report/EmbedAssets.cmake: do not edit.
#include \"engine/report/ReportAssets.h\"

#include \"cutters/Error.h\"

#include <map>

namespace engage {
namespace {
${body}
}  // namespace

const std::string& reportAsset(const std::string& name) {
  static const std::map<std::string, std::string> assets = [] {
    const std::pair<const char*, const char* const*> list[] = {
${table}    };
    std::map<std::string, std::string> m;
    for (const auto& [key, pieces] : list)
      for (const char* const* p = pieces; *p; ++p) m[key] += *p;
    return m;
  }();
  const auto it = assets.find(name);
  if (it == assets.end()) throw Error(\"no report asset named \" + name);
  return it->second;
}

}  // namespace engage
")
file(RENAME "${OUT}.part" "${OUT}")
