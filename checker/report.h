// The report on stdout, as --format asks: text (one line per check), JSON or JUnit XML (report.cpp).
#ifndef OPCCOMN_CHECK_REPORT_H
#define OPCCOMN_CHECK_REPORT_H

#include "run.h"

namespace checker {

// How many results have each Status.
struct Counts {
    int n[5] = {0, 0, 0, 0, 0};
};

// Writes the report of `results` (the selected checks', in order) in the format of run.opt.format.
void Report(const Run &run, const std::vector<Result> &results, const Counts &c);

}  // namespace checker

#endif
