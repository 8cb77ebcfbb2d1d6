// Tests of engine/report/HtmlPage.h: the encodings and the frame of the report pages.

#include "engine/report/HtmlPage.h"

#include "engine/report/ReportAssets.h"

#include <catch2/catch.hpp>

#include <sstream>
#include <string>

using namespace engage;

namespace {

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
    ++n;
  return n;
}

}  // namespace

TEST_CASE("base64 is RFC 4648's", "[report]") {
  // The test vectors of RFC 4648, section 10.
  const std::pair<const char*, const char*> vectors[] = {{"", ""},
                                                         {"f", "Zg=="},
                                                         {"fo", "Zm8="},
                                                         {"foo", "Zm9v"},
                                                         {"foob", "Zm9vYg=="},
                                                         {"fooba", "Zm9vYmE="},
                                                         {"foobar", "Zm9vYmFy"}};
  for (const auto& [plain, encoded] : vectors)
    CHECK(base64(plain, std::char_traits<char>::length(plain)) == encoded);
  // All 256 byte values: the last digits of the alphabet appear ("+" for 62, "/" for 63).
  const unsigned char bytes[3] = {0xfb, 0xef, 0xff};
  CHECK(base64(bytes, 3) == "++//");
}

TEST_CASE("text is escaped for HTML", "[report]") {
  CHECK(htmlEscape("a < b && c > \"d\"") == "a &lt; b &amp;&amp; c &gt; &quot;d&quot;");
  CHECK(htmlEscape("plain") == "plain");
}

TEST_CASE("a page holds its libraries and its data, and nothing ends a script early", "[report]") {
  // A program name or a G-code comment may hold "</script>": in the page's JSON it must not
  // end the data's script element ("<\/" is the same string in JSON).
  const std::string data = R"({"title": "x </script><b>y", "n": 1})";
  const std::string run = htmlPage(PageKind::Run, "run <1>", data);
  CHECK(run.find("<title>run &lt;1&gt;</title>") != std::string::npos);
  CHECK(run.find(R"("title": "x <\/script><b>y")") != std::string::npos);
  // Six scripts (the error counter, three libraries, the data, report.js), each closed once.
  CHECK(count(run, "</script>") == 6);
  CHECK(count(run, R"(<script id="engage-data" type="application/json">)") == 1);
  CHECK(run.find(reportAsset("three.min.js")) != std::string::npos);
  CHECK(run.find(reportAsset("dygraph.min.js")) != std::string::npos);
  CHECK(run.find(reportAsset("report.js")) != std::string::npos);
  // A batch page needs neither plots nor 3D: no libraries.
  const std::string batch = htmlPage(PageKind::Batch, "batch", "{}");
  CHECK(batch.find(reportAsset("three.min.js")) == std::string::npos);
  CHECK(count(batch, "</script>") == 3);
  CHECK_THROWS(reportAsset("missing.js"));
  // The data in pieces (a run's step tables go in so): written in order, each escaped.
  std::ostringstream os;
  writeHtmlPage(os, PageKind::Batch, "batch",
                {R"({"a": "</b>", )", R"("t": {"n": [1,2]}, )", R"("c": "</script>"})"});
  CHECK(os.str().find(R"({"a": "<\/b>", "t": {"n": [1,2]}, "c": "<\/script>"})") !=
        std::string::npos);
  CHECK(count(os.str(), "</script>") == 3);
}
