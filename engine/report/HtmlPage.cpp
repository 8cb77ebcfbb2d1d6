#include "engine/report/HtmlPage.h"

#include "cutters/Error.h"
#include "engine/report/ReportAssets.h"

namespace engage {
namespace {

/// An inlined script: the page ends a script at "</script", so none may hold it.
std::string script(const std::string& text, const char* name) {
  if (text.find("</script") != std::string::npos)
    throw Error(std::string("report asset ") + name + " holds </script and cannot be inlined");
  return "<script>\n" + text + "\n</script>\n";
}

/// Append JSON for inside <script type="application/json">: "</" becomes "<\/" (the same
/// string in JSON).
void appendScriptSafeJson(std::string& out, const std::string& json) {
  for (std::size_t i = 0; i < json.size(); ++i) {
    out += json[i];
    if (json[i] == '<' && i + 1 < json.size() && json[i + 1] == '/') out += '\\';
  }
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

std::string htmlPage(PageKind kind, const std::string& title, const std::string& dataJson) {
  const bool run = kind == PageKind::Run;
  std::string page =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      "<meta name=\"generator\" content=\"engage\">\n<title>" +
      htmlEscape(title) + "</title>\n<style>\n";
  if (run) page += reportAsset("dygraph.min.css") + "\n";
  page += reportAsset("report.css") +
          "\n</style>\n</head>\n<body>\n"
          "<noscript>This report is drawn by JavaScript: allow scripts for this file.</noscript>\n"
          // Errors of any later script are counted on the page (the tests read them).
          "<script>window.ENGAGE = {errors: []};\n"
          "window.addEventListener('error', function (e) { ENGAGE.errors.push(String(e.message)); "
          "});</script>\n";
  if (run) {
    page += script(reportAsset("dygraph.min.js"), "dygraph.min.js");
    page += script(reportAsset("three.min.js"), "three.min.js");
    page += script(reportAsset("OrbitControls.js"), "OrbitControls.js");
  }
  // The data (megabytes for a long run: 3 MB for CAMotics' tiger) straight into the page,
  // grown once, where it went through a copy and two temporaries of its size.
  page.reserve(page.size() + dataJson.size() + dataJson.size() / 64 + (1 << 16) +
               reportAsset("report.js").size());
  page += "<script id=\"engage-data\" type=\"application/json\">";
  appendScriptSafeJson(page, dataJson);
  page += "</script>\n";
  page += script(reportAsset("report.js"), "report.js");
  page += "</body>\n</html>\n";
  return page;
}

}  // namespace engage
