#include "engine/report/HtmlPage.h"

#include "cutters/Error.h"
#include "engine/report/ReportAssets.h"

#include <ostream>
#include <sstream>

namespace engage {
namespace {

/// An inlined script: the page ends a script at "</script", so none may hold it.
void writeScript(std::ostream& os, const std::string& text, const char* name) {
  if (text.find("</script") != std::string::npos)
    throw Error(std::string("report asset ") + name + " holds </script and cannot be inlined");
  os << "<script>\n" << text << "\n</script>\n";
}

/// Write JSON for inside <script type="application/json">: "</" becomes "<\/" (the same
/// string in JSON).
void writeScriptSafeJson(std::ostream& os, std::string_view json) {
  std::size_t from = 0;
  for (std::size_t i = 0; i + 1 < json.size(); ++i)
    if (json[i] == '<' && json[i + 1] == '/') {
      os.write(json.data() + from, static_cast<std::streamsize>(i + 1 - from));
      os.put('\\');
      from = i + 1;
    }
  os.write(json.data() + from, static_cast<std::streamsize>(json.size() - from));
}

}  // namespace

std::string htmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text)
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  return out;
}

std::string base64(const void* data, std::size_t bytes) {
  static const char* const kDigits =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((bytes + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes; i += 3) {
    const unsigned b0 = p[i], b1 = i + 1 < bytes ? p[i + 1] : 0u,
                   b2 = i + 2 < bytes ? p[i + 2] : 0u;
    const unsigned v = (b0 << 16) | (b1 << 8) | b2;
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += i + 1 < bytes ? kDigits[(v >> 6) & 63] : '=';
    out += i + 2 < bytes ? kDigits[v & 63] : '=';
  }
  return out;
}

void writeHtmlPage(std::ostream& os, PageKind kind, const std::string& title,
                   const std::vector<std::string_view>& dataJson) {
  const bool run = kind == PageKind::Run;
  os << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
        "<meta name=\"generator\" content=\"engage\">\n<title>"
     << htmlEscape(title) << "</title>\n<style>\n";
  if (run) os << reportAsset("dygraph.min.css") << "\n";
  os << reportAsset("report.css")
     << "\n</style>\n</head>\n<body>\n"
        "<noscript>This report is drawn by JavaScript: allow scripts for this file.</noscript>\n"
        // Errors of any later script are counted on the page (the tests read them).
        "<script>window.ENGAGE = {errors: []};\n"
        "window.addEventListener('error', function (e) { ENGAGE.errors.push(String(e.message)); "
        "});</script>\n";
  if (run) {
    for (const char* asset : {"dygraph.min.js", "three.min.js", "OrbitControls.js"})
      writeScript(os, reportAsset(asset), asset);
  }
  // The data (megabytes for a long run) straight into the file, never the whole page as a
  // string.
  os << "<script id=\"engage-data\" type=\"application/json\">";
  for (std::string_view piece : dataJson)
    writeScriptSafeJson(os, piece);
  os << "</script>\n";
  writeScript(os, reportAsset("report.js"), "report.js");
  os << "</body>\n</html>\n";
}

std::string htmlPage(PageKind kind, const std::string& title, const std::string& dataJson) {
  std::ostringstream os;
  writeHtmlPage(os, kind, title, {std::string_view(dataJson)});
  return os.str();
}

}  // namespace engage
