#pragma once
// A self-contained HTML document builder for run reports: sections, tables, notes and figures (inline SVG from
// bench/report/svg_plot.hpp / svg_raster.hpp), one embedded style sheet, no scripts, no external resources.
// The page opens offline in any browser and can be mailed as one file.
//
// Text passed as plain text is XML-escaped; SVG passed to Figure is inserted verbatim (it must be a complete
// <svg> element, as the plot functions return). Not thread-safe (one builder per report).
#include <string>
#include <utility>
#include <vector>

#include "core/util/status.hpp"

namespace rotolidar::bench {

class HtmlReport {
 public:
  explicit HtmlReport(std::string title);

  /// Opens a <section id="`id`"> with an <h2> heading; closes the previous section.
  void BeginSection(const std::string& id, const std::string& heading);
  void Paragraph(const std::string& text);
  /// A highlighted note, e.g. why a section was left out ("no truth: ...").
  void Note(const std::string& text);
  /// A table; every row should have header.size() cells (short rows are padded). Numeric-looking cells are
  /// right-aligned.
  void Table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
             const std::string& caption = "");
  /// Two-column name/value table.
  void KeyValueTable(const std::vector<std::pair<std::string, std::string>>& rows, const std::string& caption = "");
  /// An inline SVG figure with a caption.
  void Figure(const std::string& svg, const std::string& caption);
  /// Preformatted text (configs), escaped, inside a collapsible <details> block titled `summary`.
  void Preformatted(const std::string& summary, const std::string& text);

  /// The complete document (closes the open section).
  std::string Render() const;
  /// Writes Render() to `path`; the Status names the path on failure.
  Status Write(const std::string& path) const;

 private:
  std::string title_;
  std::string body_;
  bool section_open_ = false;
};

/// printf-style formatting helper for report cells ("%.3f" etc.).
std::string Fmt(const char* format, double value);

}  // namespace rotolidar::bench
