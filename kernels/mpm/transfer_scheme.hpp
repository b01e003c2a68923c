#pragma once
// Particle-grid transfer schemes of the BFEMP paper (Tables 1-3).
#include <string>

namespace bfemp {
enum class TransferScheme { APIC, PIC, FLIP };
inline const char* transfer_scheme_name(TransferScheme s) {
  return s == TransferScheme::APIC ? "APIC" : s == TransferScheme::PIC ? "PIC" : "FLIP";
}
}  // namespace bfemp
