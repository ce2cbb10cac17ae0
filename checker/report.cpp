// The report (report.h). Each format gives the same results: the text one line per check and a
// summary, JSON for a vendor's own tools, JUnit (failed checks as <failure>, not applicable and not run
// ones as <skipped>) for CI.
#include "report.h"

#include <cstdio>

// The checker is the library's version ("0.3.0-dev" while that version is in development), from the
// header, which takes it from Cargo.toml.
#define OPCCOMN_CHECK_VERSION OPCCOMN_VERSION

namespace checker {

namespace {

const char *const kStatusText[] = {"passed", "failed", "warning", "not applicable", "not run"};
const char *const kStatusTag[] = {"PASS", "FAIL", "WARN", "N/A ", "SKIP"};

std::string Json(const std::string &s) {
    std::string o = "\"";
    for (unsigned char c : s) {
        if (c == '"') o += "\\\"";
        else if (c == '\\') o += "\\\\";
        else if (c == '\n') o += "\\n";
        else if (c == '\r') o += "\\r";
        else if (c == '\t') o += "\\t";
        else if (c < 0x20) o += Format("\\u%04x", c);
        else o += static_cast<char>(c);
    }
    return o + "\"";
}

std::string Xml(const std::string &s) {
    std::string o;
    for (unsigned char c : s) {
        if (c == '<') o += "&lt;";
        else if (c == '>') o += "&gt;";
        else if (c == '&') o += "&amp;";
        else if (c == '"') o += "&quot;";
        else if (c < 0x20 && c != '\n' && c != '\t') o += ' ';
        else o += static_cast<char>(c);
    }
    return o;
}

void Out(const std::string &s) { fwrite(s.data(), 1, s.size(), stdout); }

void ReportText(const Run &run, const std::vector<Result> &results, const Counts &c) {
    Out("opccomn-check " OPCCOMN_CHECK_VERSION ": " + run.server_text + "\n");
    for (const Result &r : results) {
        std::string line = Format("%s  %-13s %-30s ", kStatusTag[r.status], r.section.c_str(), r.id.c_str());
        if (r.status == kFailed || r.status == kWarning) {
            line += "expected " + r.expected + "; got " + r.got;
            if (!r.detail.empty()) line += " (" + r.detail + ")";
        } else {
            line += r.detail;
        }
        Out(line + "\n");
    }
    Out(Format("summary: %d passed, %d failed, %d warnings, %d not applicable, %d not run\n", c.n[kPassed], c.n[kFailed],
               c.n[kWarning], c.n[kNotApplicable], c.n[kNotRun]));
}

void ReportJson(const Run &run, const std::vector<Result> &results, const Counts &c) {
    Out("{\n  \"tool\": \"opccomn-check\",\n  \"version\": \"" OPCCOMN_CHECK_VERSION "\",\n");
    Out("  \"server\": {\"argument\": " + Json(Utf8(run.opt.server.c_str())) + ", \"clsid\": " +
        Json(run.facts.clsid_known ? GuidText(run.facts.clsid) : "") + ", \"host\": " + Json(Utf8(run.opt.host.c_str())) +
        ", \"kind\": " + Json(KindName(run.kind)) + "},\n  \"checks\": [\n");
    for (size_t i = 0; i < results.size(); i++) {
        const Result &r = results[i];
        Out("    {\"id\": " + Json(r.id) + ", \"section\": " + Json(r.section) + ", \"title\": " + Json(r.title) +
            ", \"status\": " + Json(kStatusText[r.status]));
        if (r.status == kFailed || r.status == kWarning) Out(", \"expected\": " + Json(r.expected) + ", \"got\": " + Json(r.got));
        Out(", \"detail\": " + Json(r.detail) + "}" + (i + 1 < results.size() ? "," : "") + "\n");
    }
    Out(Format("  ],\n  \"summary\": {\"passed\": %d, \"failed\": %d, \"warnings\": %d, \"not_applicable\": %d, \"not_run\": %d}\n}\n",
               c.n[kPassed], c.n[kFailed], c.n[kWarning], c.n[kNotApplicable], c.n[kNotRun]));
}

void ReportJunit(const Run &run, const std::vector<Result> &results, const Counts &c) {
    Out("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    Out(Format("<testsuites name=\"opccomn-check\" tests=\"%d\" failures=\"%d\" skipped=\"%d\">\n", static_cast<int>(results.size()),
               c.n[kFailed], c.n[kNotApplicable] + c.n[kNotRun]));
    Out(Format("  <testsuite name=\"%s\" tests=\"%d\" failures=\"%d\" errors=\"0\" skipped=\"%d\">\n", Xml(run.server_text).c_str(),
               static_cast<int>(results.size()), c.n[kFailed], c.n[kNotApplicable] + c.n[kNotRun]));
    for (const Result &r : results) {
        std::string group = r.id.substr(0, r.id.find('.'));
        Out("    <testcase classname=\"opccomn-check." + Xml(group) + "\" name=\"" + Xml(r.id) + " (" + Xml(r.section) + ")\">");
        if (r.status == kFailed)
            Out("<failure message=\"" + Xml("expected " + r.expected + "; got " + r.got) + "\">" + Xml(r.title + ". " + r.detail) + "</failure>");
        else if (r.status == kNotApplicable || r.status == kNotRun)
            Out("<skipped message=\"" + Xml(kStatusText[r.status] + std::string(": ") + r.detail) + "\"/>");
        else if (r.status == kWarning)
            Out("<system-out>" + Xml("warning: expected " + r.expected + "; got " + r.got + ". " + r.detail) + "</system-out>");
        else
            Out("<system-out>" + Xml(r.detail) + "</system-out>");
        Out("</testcase>\n");
    }
    Out("  </testsuite>\n</testsuites>\n");
}

}  // namespace

void Report(const Run &run, const std::vector<Result> &results, const Counts &c) {
    if (run.opt.format == "json") ReportJson(run, results, c);
    else if (run.opt.format == "junit") ReportJunit(run, results, c);
    else ReportText(run, results, c);
}

}  // namespace checker
