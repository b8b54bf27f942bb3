#include "bench/report/html_report.hpp"

#include <cctype>
#include <cstdio>
#include <fstream>

#include "bench/report/svg_plot.hpp"

namespace rotolidar::bench {
namespace {

constexpr const char* kStyle = R"(
body { font-family: "DejaVu Sans", Arial, sans-serif; margin: 24px auto; max-width: 1100px; color: #222; }
h1 { font-size: 22px; border-bottom: 2px solid #1f77b4; padding-bottom: 6px; }
h2 { font-size: 17px; margin-top: 28px; border-bottom: 1px solid #ccc; padding-bottom: 3px; }
table { border-collapse: collapse; margin: 8px 0 14px 0; font-size: 13px; }
th, td { border: 1px solid #ccc; padding: 3px 9px; }
th { background: #f0f4f8; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
caption { caption-side: top; text-align: left; font-style: italic; color: #555; padding-bottom: 3px; }
figure { display: inline-block; margin: 6px 12px 12px 0; vertical-align: top; }
figcaption { font-size: 12px; color: #555; max-width: 640px; }
.note { background: #fff8e1; border-left: 4px solid #f0ad4e; padding: 6px 10px; font-size: 13px; }
pre { background: #f7f7f7; padding: 8px; font-size: 12px; overflow-x: auto; }
footer { margin-top: 30px; font-size: 11px; color: #888; }
)";

bool LooksNumeric(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!(std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '+' || c == 'e' || c == '%' ||
          c == ' ' || c == 'x'))
      return false;
  return std::isdigit(static_cast<unsigned char>(s[0])) || s[0] == '-' || s[0] == '+';
}

}  // namespace

HtmlReport::HtmlReport(std::string title) : title_(std::move(title)) {}

void HtmlReport::BeginSection(const std::string& id, const std::string& heading) {
  if (section_open_) body_ += "</section>\n";
  body_ += "<section id=\"" + XmlEscape(id) + "\">\n<h2>" + XmlEscape(heading) + "</h2>\n";
  section_open_ = true;
}

void HtmlReport::Paragraph(const std::string& text) { body_ += "<p>" + XmlEscape(text) + "</p>\n"; }

void HtmlReport::Note(const std::string& text) { body_ += "<p class=\"note\">" + XmlEscape(text) + "</p>\n"; }

void HtmlReport::Table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
                       const std::string& caption) {
  body_ += "<table>\n";
  if (!caption.empty()) body_ += "<caption>" + XmlEscape(caption) + "</caption>\n";
  body_ += "<tr>";
  for (const std::string& h : header) body_ += "<th>" + XmlEscape(h) + "</th>";
  body_ += "</tr>\n";
  for (const auto& row : rows) {
    body_ += "<tr>";
    for (size_t i = 0; i < std::max(header.size(), row.size()); ++i) {
      const std::string cell = i < row.size() ? row[i] : "";
      body_ += LooksNumeric(cell) ? "<td class=\"num\">" : "<td>";
      body_ += XmlEscape(cell) + "</td>";
    }
    body_ += "</tr>\n";
  }
  body_ += "</table>\n";
}

void HtmlReport::KeyValueTable(const std::vector<std::pair<std::string, std::string>>& rows,
                               const std::string& caption) {
  std::vector<std::vector<std::string>> cells;
  for (const auto& [k, v] : rows) cells.push_back({k, v});
  Table({"quantity", "value"}, cells, caption);
}

void HtmlReport::Figure(const std::string& svg, const std::string& caption) {
  body_ += "<figure>\n" + svg + "<figcaption>" + XmlEscape(caption) + "</figcaption>\n</figure>\n";
}

void HtmlReport::Preformatted(const std::string& summary, const std::string& text) {
  body_ += "<details><summary>" + XmlEscape(summary) + "</summary>\n<pre>" + XmlEscape(text) + "</pre></details>\n";
}

std::string HtmlReport::Render() const {
  std::string out = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n<title>" +
                    XmlEscape(title_) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n<h1>" +
                    XmlEscape(title_) + "</h1>\n" + body_;
  if (section_open_) out += "</section>\n";
  out += "<footer>Written by rotolidar (bench/report). Self-contained: inline SVG and base64 PNG, no scripts."
         "</footer>\n</body>\n</html>\n";
  return out;
}

Status HtmlReport::Write(const std::string& path) const {
  std::ofstream file(path, std::ios::binary);
  file << Render();
  return file ? Status::Ok() : Status::Error(path + ": cannot write the report");
}

std::string Fmt(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, value);
  return buf;
}

}  // namespace rotolidar::bench
