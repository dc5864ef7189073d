// Where the measurements sit on the body: keypoint layouts and IMU sites, and their files.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "mocap/ground.h"
#include "mocap/sites.h"

namespace mocap::bindings {
namespace {

KeypointLayout WithOffsets(KeypointLayout l, const Eigen::MatrixX3d& offsets) {
  if (offsets.rows() != l.size()) throw std::invalid_argument("one offset per keypoint");
  for (int k = 0; k < l.size(); ++k) l.sites[k].offset = offsets.row(k).transpose();
  return l;
}

void BindLayout(py::module_& m) {
  py::class_<KeypointLayout>(m, "KeypointLayout")
      .def_static("load",
                  [](const std::string& path, const Skeleton& s) {
                    return Checked<KeypointLayout>([&](KeypointLayout* out, std::string* e) {
                      return LoadKeypointLayoutJson(path, s, out, e);
                    });
                  })
      .def("scaled_to", &KeypointLayout::ScaledTo)
      .def_readonly("name", &KeypointLayout::name)
      .def_readonly("names", &KeypointLayout::names)
      .def_property_readonly("bones",
                             [](const KeypointLayout& l) {
                               std::vector<int> b;
                               for (const auto& s : l.sites) b.push_back(s.bone);
                               return b;
                             })
      .def_property_readonly("offsets",
                             [](const KeypointLayout& l) {
                               Eigen::MatrixX3d o(l.size(), 3);
                               for (int k = 0; k < l.size(); ++k)
                                 o.row(k) = l.sites[k].offset.transpose();
                               return o;
                             })
      .def("with_offsets", &WithOffsets,
           "A copy whose sites have these (K, 3) offsets (m, bone frames).")
      .def("__len__", &KeypointLayout::size);
  m.def("layout_to_json", &KeypointLayoutToJson, py::arg("skeleton"), py::arg("layout"),
        "The layout file (mocap.layout/1), its offsets as they are for the skeleton.");
}

void BindImuSites(py::module_& m) {
  py::class_<ImuSite>(m, "ImuSite")
      .def(py::init<>())
      .def_readwrite("name", &ImuSite::name)
      .def_readwrite("bone", &ImuSite::bone)
      .def_readwrite("mount", &ImuSite::mount, "sensor -> bone rotation")
      .def_readwrite("offset", &ImuSite::offset, "bone frame, metres")
      .def_readwrite("reference", &ImuSite::reference, "IMU reference frame -> world rotation");
  m.def("load_imu_sites", [](const std::string& path, const Skeleton& s) {
    return Checked<std::vector<ImuSite>>([&](std::vector<ImuSite>* out, std::string* e) {
      return LoadImuSitesJson(path, s, out, e);
    });
  });
  m.def("imu_sites_to_json", &ImuSitesToJson, py::arg("skeleton"), py::arg("imus"),
        "The IMU set file (mocap.imus/1) of IMU sites.");
}

// The feet's contact sites and the floor under poses (ground.h).
void BindGround(py::module_& m) {
  m.def(
      "foot_contact_sites",
      [](const Skeleton& s) {
        std::vector<std::pair<int, Eigen::Vector3d>> out;
        for (const Site& site : FootContactSites(s)) out.emplace_back(site.bone, site.offset);
        return out;
      },
      py::arg("skeleton"),
      "E_G's contact sites, (bone, offset m in the bone frame): heel, ball, toe tip per foot.");
  m.def(
      "floor_height",
      [](const Skeleton& s, const Eigen::MatrixXd& thetas) {
        std::vector<Eigen::VectorXd> poses;
        for (int f = 0; f < thetas.rows(); ++f) poses.push_back(thetas.row(f).transpose());
        return FloorHeight(s, poses);
      },
      py::arg("skeleton"), py::arg("thetas"),
      "The floor under (F, pose_dim) poses (world z, m): the median of each pose's lowest foot "
      "contact site; NaN when unknown (no feet, no finite pose, the wrong pose size).");
}

}  // namespace

void BindSites(py::module_& m) {
  BindLayout(m);
  BindImuSites(m);
  BindGround(m);
}

}  // namespace mocap::bindings
