#pragma once
// A MuJoCo model + data loaded from MJCF text (through a virtual file), for the sensor tests and
// benchmarks. Throws std::runtime_error with MuJoCo's message if the text is rejected.

#include <mujoco/mujoco.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace concert::sim::test {

class MujocoScene {
 public:
  explicit MujocoScene(const std::string& mjcf) {
    mjVFS vfs;
    mj_defaultVFS(&vfs);
    const char* file = "scene.xml";
    if (mj_makeEmptyFileVFS(&vfs, file, static_cast<int>(mjcf.size())) != 0) {
      throw std::runtime_error("MujocoScene: could not allocate the virtual file");
    }
    std::memcpy(vfs.filedata[0], mjcf.data(), mjcf.size());
    char error[1000] = "";
    m_ = mj_loadXML(file, &vfs, error, sizeof(error));
    mj_deleteVFS(&vfs);
    if (m_ == nullptr) {
      throw std::runtime_error(std::string("MujocoScene: MuJoCo rejected the MJCF: ") + error);
    }
    d_ = mj_makeData(m_);
    mj_forward(m_, d_);
  }
  ~MujocoScene() {
    mj_deleteData(d_);
    mj_deleteModel(m_);
  }
  MujocoScene(const MujocoScene&) = delete;
  MujocoScene& operator=(const MujocoScene&) = delete;

  [[nodiscard]] mjModel* m() const { return m_; }
  [[nodiscard]] mjData* d() const { return d_; }

 private:
  mjModel* m_{nullptr};
  mjData* d_{nullptr};
};

/// A whole MJCF document: `worldbody` children, optional `sensors` (children of <sensor>) and
/// `assets` (children of <asset>); gravity -9.81 along z, angles in radians.
inline std::string mjcf_document(const std::string& worldbody, const std::string& sensors = "",
                                 const std::string& assets = "") {
  std::string xml =
      "<mujoco model=\"test\">\n<compiler angle=\"radian\"/>\n<option timestep=\"0.001\" "
      "gravity=\"0 0 -9.81\"/>\n";
  if (!assets.empty()) {
    xml += "<asset>\n" + assets + "</asset>\n";
  }
  xml += "<worldbody>\n" + worldbody + "</worldbody>\n";
  if (!sensors.empty()) {
    xml += "<sensor>\n" + sensors + "</sensor>\n";
  }
  return xml + "</mujoco>\n";
}

}  // namespace concert::sim::test
