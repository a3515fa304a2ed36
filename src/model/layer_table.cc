#include "model/layer_table.h"

#include <cmath>
#include <fstream>
#include <sstream>

namespace weaver {
namespace {

Status bad_line(const std::string& name, int line, const std::string& what) {
  return Status::Corruption(name + ":" + std::to_string(line) + ": " + what);
}

// The numbers of one line, or an error naming the first that is not one.
Status numbers_of(const std::string& text, const std::string& name, int line,
                  std::vector<double>* out) {
  out->clear();
  std::istringstream in(text);
  std::string word;
  while (in >> word) {
    size_t used = 0;
    double v = 0;
    try {
      v = std::stod(word, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != word.size()) return bad_line(name, line, "'" + word + "' is not a number");
    out->push_back(v);
  }
  return Status::Ok();
}

}  // namespace

Status parse_layer_table(const std::string& text, const std::string& name, LayerTable* out) {
  *out = LayerTable{};
  std::istringstream in(text);
  std::string line;
  std::vector<double> v;
  static const char* fields[] = {"Vp", "Vs", "density", "Qp", "Qs"};
  for (int n = 1; std::getline(in, line); ++n) {
    line = line.substr(0, line.find('#'));
    WEAVER_RETURN_IF_ERROR(numbers_of(line, name, n, &v));
    if (v.empty()) continue;
    if (v.size() != 4 && v.size() != 6) {
      return bad_line(
          name, n,
          "a layer is 'top_depth vp vs rho [qp qs]', not " + std::to_string(v.size()) + " numbers");
    }
    const bool q = v.size() == 6;
    if (!out->layers.empty() && q != out->has_q) {
      return bad_line(name, n, "give Qp and Qs on every layer or on none");
    }
    out->has_q = q;
    Layer l;
    l.top_m = v[0];
    if (!std::isfinite(l.top_m)) return bad_line(name, n, "the top depth must be finite");
    if (out->layers.empty() && l.top_m != 0) {
      return bad_line(
          name, n, "the first layer's top must be 0 (the surface), not " + std::to_string(l.top_m));
    }
    if (!out->layers.empty() && !(l.top_m > out->layers.back().top_m)) {
      char buf[120];
      std::snprintf(buf, sizeof buf, "tops must increase (%g after %g)", l.top_m,
                    out->layers.back().top_m);
      return bad_line(name, n, buf);
    }
    for (size_t f = 1; f < v.size(); ++f) {
      const bool ok = std::isfinite(v[f]) && (f <= 3 ? v[f] > 0 : v[f] >= 0);
      if (!ok) {
        return bad_line(name, n,
                        std::string(fields[f - 1]) + " " + std::to_string(v[f]) +
                            (f <= 3 ? " must be positive and finite" : " must be finite, >= 0"));
      }
      l.values[f - 1] = static_cast<float>(v[f]);
    }
    out->layers.push_back(l);
  }
  if (out->layers.empty()) return Status::Corruption(name + ": no layers");
  return Status::Ok();
}

Status read_layer_table(const std::string& path, LayerTable* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::NotFound(path + ": cannot open the layer table");
  // A table is a few dozen lines; a huge file is not one.
  in.seekg(0, std::ios::end);
  if (in.tellg() > std::streampos(16 << 20)) {
    return Status::Corruption(path + ": larger than 16 MB: not a layer table");
  }
  in.seekg(0);
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return Status::IOError(path + ": cannot read the layer table");
  return parse_layer_table(text.str(), path, out);
}

}  // namespace weaver
