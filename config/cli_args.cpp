#include "config/cli_args.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>

namespace radar_emu::config {

double parse_number(std::string_view s, std::string_view option) {
  // std::from_chars for double is in GCC 12's libstdc++.
  double v = 0.0;
  const auto* end = s.data() + s.size();
  const auto [ptr, ec] = std::from_chars(s.data(), end, v);
  if (ec != std::errc() || ptr != end || !std::isfinite(v)) {
    throw std::invalid_argument(std::string(option) + ": '" + std::string(s) +
                                "' is not a finite number");
  }
  return v;
}

std::vector<std::string_view> split(std::string_view s, char sep) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t pos = s.find(sep, start);
    out.push_back(s.substr(start, pos == std::string_view::npos ? pos : pos - start));
    if (pos == std::string_view::npos)
      return out;
    start = pos + 1;
  }
}

std::pair<double, double> parse_pair(std::string_view text, std::string_view option) {
  const auto parts = split(text, ',');
  if (parts.size() != 2)
    throw std::invalid_argument(std::string(option) + ": expected two numbers A,B (got '" +
                                std::string(text) + "')");
  return {parse_number(parts[0], option), parse_number(parts[1], option)};
}

std::vector<double> parse_sweep(std::string_view text, std::string_view option) {
  const auto parts = split(text, ':');
  if (parts.size() == 1)
    return {parse_number(parts[0], option)};
  if (parts.size() != 3) {
    throw std::invalid_argument(std::string(option) + ": expected X or START:STOP:N, got '" +
                                std::string(text) + "'");
  }
  const double a = parse_number(parts[0], option), b = parse_number(parts[1], option);
  const double n_real = parse_number(parts[2], option);
  if (n_real < 1.0 || n_real > 1e6 || n_real != std::floor(n_real)) {
    throw std::invalid_argument(std::string(option) +
                                ": N must be a whole number in 1..1e6, got '" +
                                std::string(parts[2]) + "'");
  }
  const auto n = static_cast<std::size_t>(n_real);
  if (n > 1 && a == b)
    throw std::invalid_argument(std::string(option) + ": START equals STOP with N > 1");
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i)
    out[i] = n == 1 ? a : a + (b - a) * static_cast<double>(i) / static_cast<double>(n - 1);
  return out;
}

}  // namespace radar_emu::config
