#include "isowave/codec/camera.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/core/mesh_io.h"

namespace isowave {

namespace {

constexpr double kPi = 3.14159265358979323846;

// The camera's frame: d along the view, r to the right, u up (orthonormal).
struct ViewFrame {
  Vec3 d, r, u;
};
ViewFrame view_frame(const Camera& c) {
  ViewFrame f;
  f.d = normalized(c.target - c.position);
  f.r = normalized(cross(f.d, c.up));
  f.u = cross(f.r, f.d);
  return f;
}

// A strict reader of the camera's JSON: one object of numbers and arrays of numbers.
class CameraJson {
 public:
  CameraJson(const std::string& text, const std::string& name) : text_(text), name_(name) {}

  std::map<std::string, std::vector<double>> object() {
    std::map<std::string, std::vector<double>> values;
    expect('{');
    if (peek() == '}') fail("holds no camera");
    for (;;) {
      const std::string key = string();
      expect(':');
      if (values.count(key)) fail("holds \"" + key + "\" twice");
      values[key] = value();
      if (peek() == ',') {
        ++at_;
        continue;
      }
      expect('}');
      break;
    }
    if (peek() != '\0') fail("has text after the camera object");
    return values;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(ErrorKind::Format, name_ + ": the camera " + what + " (at character " + std::to_string(at_) + ")");
  }
  char peek() {
    while (at_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[at_]))) ++at_;
    return at_ < text_.size() ? text_[at_] : '\0';
  }
  void expect(char c) {
    if (peek() != c) fail(std::string("expects '") + c + "'");
    ++at_;
  }
  std::string string() {
    expect('"');
    const std::size_t end = text_.find('"', at_);
    if (end == std::string::npos) fail("has an unterminated key");
    std::string s = text_.substr(at_, end - at_);
    at_ = end + 1;
    return s;
  }
  double number() {
    peek();
    const char* begin = text_.c_str() + at_;
    char* end = nullptr;
    const double v = std::strtod(begin, &end);
    if (end == begin || !std::isfinite(v)) fail("expects a finite number");
    at_ += static_cast<std::size_t>(end - begin);
    return v;
  }
  std::vector<double> value() {
    if (peek() != '[') return {number()};
    ++at_;
    std::vector<double> values;
    if (peek() == ']') fail("holds an empty array");
    for (;;) {
      values.push_back(number());
      if (peek() == ',') {
        ++at_;
        continue;
      }
      expect(']');
      return values;
    }
  }

  const std::string& text_;
  const std::string& name_;
  std::size_t at_ = 0;
};

}  // namespace

double Camera::pixels_per_unit(double depth) const {
  return 0.5 * height / std::tan(0.5 * fov_degrees * kPi / 180) / depth;
}

bool Camera::box_outside(const Vec3& lo, const Vec3& hi) const {
  const ViewFrame f = view_frame(*this);
  const double tan_v = std::tan(0.5 * fov_degrees * kPi / 180), tan_h = tan_v * width / height;
  // Per plane (behind; left, right, below, above), whether every corner is outside it.
  std::array<bool, 5> all_out;
  all_out.fill(true);
  for (int k = 0; k < 8; ++k) {
    const Vec3 corner{(k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z};
    const Vec3 v = corner - position;
    const double z = dot(v, f.d), x = dot(v, f.r), y = dot(v, f.u);
    const bool out[5] = {z <= 0, x < -z * tan_h, x > z * tan_h, y < -z * tan_v, y > z * tan_v};
    for (int p = 0; p < 5; ++p) all_out[static_cast<std::size_t>(p)] = all_out[static_cast<std::size_t>(p)] && out[p];
  }
  return std::any_of(all_out.begin(), all_out.end(), [](bool b) { return b; });
}

Camera parse_camera(const std::string& json, const std::string& name) {
  const std::map<std::string, std::vector<double>> values = CameraJson(json, name).object();
  const auto get = [&](const char* key, std::size_t count) {
    const auto it = values.find(key);
    if (it == values.end()) throw Error(ErrorKind::Format, name + ": the camera has no \"" + key + "\"");
    if (it->second.size() != count)
      throw Error(ErrorKind::Format, name + ": the camera's \"" + key + "\" must hold " + std::to_string(count) +
                                         (count == 1 ? " number" : " numbers"));
    return it->second;
  };
  for (const auto& [key, value] : values)
    if (key != "position" && key != "target" && key != "up" && key != "fov" && key != "viewport")
      throw Error(ErrorKind::Format, name + ": the camera has an unknown key \"" + key + "\"");
  Camera camera;
  const std::vector<double> p = get("position", 3), t = get("target", 3), u = get("up", 3), v = get("viewport", 2);
  camera.position = {p[0], p[1], p[2]};
  camera.target = {t[0], t[1], t[2]};
  camera.up = {u[0], u[1], u[2]};
  camera.fov_degrees = get("fov", 1)[0];
  if (v[0] != std::floor(v[0]) || v[1] != std::floor(v[1]) || !(v[0] >= 1 && v[0] <= 1e5) || !(v[1] >= 1 && v[1] <= 1e5))
    throw Error(ErrorKind::InvalidArgument, name + ": the camera's viewport must be two whole numbers of pixels, 1 to 100000");
  camera.width = static_cast<int>(v[0]);
  camera.height = static_cast<int>(v[1]);
  try {
    check_camera(camera);
  } catch (const Error& error) {
    throw Error(error.kind(), name + ": " + error.what());
  }
  return camera;
}

Camera read_camera(const std::string& path) { return parse_camera(read_file_bytes(path), path); }

void check_camera(const Camera& camera) {
  if (!(camera.fov_degrees > 0 && camera.fov_degrees < 180))
    throw Error(ErrorKind::InvalidArgument, "the camera's fov must be in (0, 180) degrees");
  if (camera.width < 1 || camera.height < 1) throw Error(ErrorKind::InvalidArgument, "the camera's viewport must be positive");
  const Vec3 d = camera.target - camera.position;
  if (!(norm(d) > 0)) throw Error(ErrorKind::InvalidArgument, "the camera's target must differ from its position");
  if (!(norm(cross(normalized(d), camera.up)) > 1e-9))
    throw Error(ErrorKind::InvalidArgument, "the camera's up must not lie along its view direction");
}

}  // namespace isowave
