// .pvd collections: the input is the collection, in a directory holding two small meshes it may name (and
// itself, as in.pvd). Nesting, cycles, patterns, FIFOs and repeated parts must end in a uvr::Error.
#include "fuzz_input.h"
#include "io/mesh_io.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace {

const char *kTetVtu =
    R"(<VTKFile type="UnstructuredGrid"><UnstructuredGrid><Piece NumberOfPoints="4" NumberOfCells="1">
<PointData><DataArray type="Float32" Name="f" format="ascii">0 1 2 3</DataArray></PointData>
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 0 0 1</DataArray></Points>
<Cells><DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 3</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">4</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">10</DataArray></Cells></Piece></UnstructuredGrid></VTKFile>)";

std::string made; // removed at exit: nothing left behind

/// The directory the collection lives in, made once: a.vtu, b.vtu, and in.pvd linked to the input.
const std::string &directory(const std::string &input) {
  static const std::string dir = [&] {
    char name[] = "/tmp/uvr_fuzz_pvd_XXXXXX";
    if (!::mkdtemp(name))
      std::abort();
    const std::string d = name;
    std::ofstream(d + "/a.vtu") << kTetVtu;
    std::ofstream(d + "/b.vtu") << kTetVtu;
    if (::symlink(input.c_str(), (d + "/in.pvd").c_str()) != 0)
      std::abort();
    made = d;
    std::atexit([] { std::filesystem::remove_all(made); });
    return d;
  }();
  return dir;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const std::string &input = uvr::fuzz::inputFile(data, size);
  const std::string &dir = directory(input);
  try {
    uvr::loadMesh(dir + "/in.pvd");
    uvr::timeStepCount(dir + "/in.pvd");
  } catch (const uvr::Error &) {
  }
  return 0;
}
