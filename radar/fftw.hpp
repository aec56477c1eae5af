#pragma once
// FFTW 3 buffers and plans as RAII handles, and the one lock every planner call takes.
//
// FFTW's thread safety (FFTW 3.3 manual, sec. 5.4 "Thread safety"): only fftw_execute and its
// new-array variants (fftw_execute_dft) may run on several threads at once; the planner and
// fftw_destroy_plan touch shared state and must be called from one thread at a time. Every
// plan in the radar library is therefore made and destroyed through Plan below, under
// planner_mutex(), so that the sensor's setup, the range profile, ISAR, SAR and the IRF
// measurement may run on different threads of one process (the Python module, the tests).
#include <fftw3.h>

#include <algorithm>
#include <complex>
#include <cstddef>
#include <memory>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>
#include <utility>

namespace radar_emu::radar::fftw {

/// The one lock around FFTW's planner (an inline function: one mutex across the library).
inline std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}

struct Free {
  void operator()(void* p) const noexcept { fftw_free(p); }
};

/// n complex samples from fftw_malloc (aligned for SIMD), zeroed.
using ComplexBuffer = std::unique_ptr<std::complex<double>[], Free>;

/// Throws std::bad_alloc when FFTW cannot allocate.
[[nodiscard]] inline ComplexBuffer complex_buffer(std::size_t n) {
  auto* p = static_cast<std::complex<double>*>(fftw_malloc(sizeof(std::complex<double>) * n));
  if (p == nullptr)
    throw std::bad_alloc();
  std::fill(p, p + n, std::complex<double>{});
  return ComplexBuffer(p);
}

/// std::complex<double> and fftw_complex share their layout (C++ [complex.numbers] p4, FFTW
/// manual sec. 4.1.1).
[[nodiscard]] inline fftw_complex* as_fftw(std::complex<double>* p) noexcept {
  return reinterpret_cast<fftw_complex*>(p);
}

/// An FFTW plan, made by `make()` (a call of one of fftw_plan_*) under the planner lock and
/// destroyed under it. Throws std::runtime_error naming `what` when FFTW cannot plan.
class Plan {
 public:
  Plan() = default;  ///< no plan (execute() must not be called)
  template <class MakePlan>
  Plan(const char* what, MakePlan&& make) {
    {
      const std::lock_guard<std::mutex> lock(planner_mutex());
      plan_ = std::forward<MakePlan>(make)();
    }
    if (plan_ == nullptr)
      throw std::runtime_error(std::string(what) + ": FFTW could not plan the transform");
  }
  ~Plan() {
    if (plan_ != nullptr) {
      const std::lock_guard<std::mutex> lock(planner_mutex());
      fftw_destroy_plan(plan_);
    }
  }
  Plan(const Plan&) = delete;
  Plan& operator=(const Plan&) = delete;
  Plan(Plan&& o) noexcept : plan_(std::exchange(o.plan_, nullptr)) {}
  Plan& operator=(Plan&& o) noexcept {
    if (this != &o) {
      this->~Plan();
      plan_ = std::exchange(o.plan_, nullptr);
    }
    return *this;
  }

  /// The transform on the arrays it was planned with.
  void execute() const noexcept { fftw_execute(plan_); }
  /// The transform on other arrays of the same size and alignment (thread-safe).
  void execute(std::complex<double>* in, std::complex<double>* out) const noexcept {
    fftw_execute_dft(plan_, as_fftw(in), as_fftw(out));
  }
  [[nodiscard]] fftw_plan get() const noexcept { return plan_; }

 private:
  fftw_plan plan_ = nullptr;
};

}  // namespace radar_emu::radar::fftw
