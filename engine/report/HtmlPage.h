#pragma once
/// \file HtmlPage.h
/// The frame of engage's HTML reports: one self-contained file (scripts and styles inlined,
/// ReportAssets.h) that opens from disk with no network, its data as JSON in the page, drawn by
/// report.js. Also the encodings the data uses.

#include <cstddef>
#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

namespace engage {

/// What a page shows.
enum class PageKind {
  Run,   ///< one run: summary, plots along the path (dygraphs), 3D view of the stock (three.js)
  Batch  ///< a batch: one row per job with its status, figures and a link to its report
};

/// Write the page: `title` (plain text) and `dataJson` (a JSON object, read by report.js as
/// ENGAGE.data, in consecutive pieces that no "</" straddles) with the libraries `kind` needs.
void writeHtmlPage(std::ostream& os, PageKind kind, const std::string& title,
                   const std::vector<std::string_view>& dataJson);
/// The same page as a string.
std::string htmlPage(PageKind kind, const std::string& title, const std::string& dataJson);

/// Standard base64 (RFC 4648, padded) of `bytes` bytes at `data`: how the page carries
/// arrays of numbers (decoded into typed arrays, little-endian as written on x86 and ARM).
std::string base64(const void* data, std::size_t bytes);

/// Text with &, <, >, " escaped for HTML.
std::string htmlEscape(const std::string& text);

}  // namespace engage
