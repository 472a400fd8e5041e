// libFuzzer target: the scene-rule checker. The bytes drive a small scene
// writer (geoms of every primitive type, free and hinged bodies, actuators,
// equality constraints and tendons, touching the rig's joints and bodies or
// not, with numbers that include 0, negatives, huge values, NaN and
// infinities); every scene either passes the checks a load applies or is
// refused with a SceneError: never a crash, a hang or another exception.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "scenes/catalog.h"
#include "sim/simulation.h"

namespace {

class Bytes {
 public:
  Bytes(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool empty() const { return pos_ >= size_; }
  uint8_t Byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  // A number as MJCF text: ordinary values, edges and non-finite ones.
  std::string Number() {
    static const char* const kSpecial[] = {"0",   "-0",  "1e-12", "0.001", "0.05", "0.3",
                                           "1",   "2.5", "-1",    "-0.2",  "1e6",  "1e300",
                                           "nan", "inf", "-inf",  "1e-300"};
    const uint8_t b = Byte();
    if (b < 128) return kSpecial[b % 16];
    char text[32];
    std::snprintf(text, sizeof text, "%.4g", (b - 192) / 16.0 + (Byte() - 128) / 512.0);
    return text;
  }
  std::string Numbers(int n) {
    std::string s;
    for (int i = 0; i < n; ++i) s += (i ? " " : "") + Number();
    return s;
  }
  template <size_t N>
  const char* Pick(const char* const (&names)[N]) {
    return names[Byte() % N];
  }

 private:
  const uint8_t* data_;
  size_t size_, pos_ = 0;
};

const char* const kTypes[] = {"box", "sphere", "capsule", "cylinder", "ellipsoid", "plane"};
const char* const kJoints[] = {"tavt_left_baseline", "tavt_left_pan", "tavt_right_tilt",
                               "own_hinge", "own_slide"};
const char* const kBodies[] = {"tavt_rail", "tavt_left_tilt", "tavt_right_carriage", "own_body",
                               "world"};

std::string SceneXml(Bytes& in) {
  std::ostringstream world, extra;
  world
      << "<body name=\"own_body\" pos=\"0 1.5 0\"><joint name=\"own_hinge\" type=\"hinge\"/>"
         "<joint name=\"own_slide\" type=\"slide\"/><geom type=\"sphere\" size=\"0.05\"/></body>\n";
  for (int i = 0; i < 6 && !in.empty(); ++i) {
    switch (in.Byte() % 6) {
      case 0:
        world << "<geom type=\"" << in.Pick(kTypes) << "\" size=\"" << in.Numbers(3) << "\" pos=\""
              << in.Numbers(3) << "\" euler=\"" << in.Numbers(3) << "\"/>\n";
        break;
      case 1:
        world << "<body pos=\"" << in.Numbers(3) << "\"><freejoint/><geom type=\""
              << in.Pick(kTypes) << "\" size=\"" << in.Numbers(3) << "\"/></body>\n";
        break;
      case 2:
        extra << "<actuator><motor joint=\"" << in.Pick(kJoints) << "\" gear=\"" << in.Number()
              << "\"/></actuator>\n";
        break;
      case 3:
        extra << "<equality><joint joint1=\"" << in.Pick(kJoints) << "\" joint2=\""
              << in.Pick(kJoints) << "\"/></equality>\n";
        break;
      case 4:
        extra << "<equality><weld body1=\"" << in.Pick(kBodies) << "\" body2=\"" << in.Pick(kBodies)
              << "\"/></equality>\n";
        break;
      default:
        extra << "<tendon><fixed name=\"t" << i << "\"><joint joint=\"" << in.Pick(kJoints)
              << "\" coef=\"" << in.Number() << "\"/></fixed></tendon><actuator><motor tendon=\"t"
              << i << "\"/></actuator>\n";
    }
  }
  return "<mujoco>\n<include file=\"tavt.xml\"/>\n<worldbody>\n" + world.str() + "</worldbody>\n" +
         extra.str() + "</mujoco>\n";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Bytes in(data, size);
  const std::string xml = SceneXml(in);
  try {
    sim::Simulation::CheckScene("fuzz.xml", xml, {}, scenes::TextureProvider());
  } catch (const sim::SceneError&) {
  }
  return 0;
}
