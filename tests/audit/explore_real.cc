#include <cstdio>
#include <iostream>
#include "tactforce/audit/audit.h"
using namespace tactforce::audit;
int main(int argc, char** argv) {
  auto d = ReadMeasuredCsv(argv[1]);
  if (!d.ok()) { std::cerr << d.status() << "\n"; return 1; }
  AuditOptions o; o.reading_units = "ADC counts"; o.downstream_gain = false;
  auto r = RunAudit(*d, o);
  if (!r.ok()) { std::cerr << r.status() << "\n"; return 1; }
  std::cout << FormatAuditSummary(*r);
  for (auto& c : r->candidates) printf("  round %d %-12s rms %.4g bic %.2f %s\n", c.round, c.effect.c_str(), c.heldout_rms, c.bic, c.accepted ? "*" : "");
  if (argc > 2) { auto st = WriteAuditReport(*r, argv[2]); std::cout << st << "\n"; }
}
