// uvr's public interface: everything a program that renders unstructured volumes with uvr needs.
//
//   uvr::VolumeMesh mesh = uvr::VolumeMesh::load("disk_out_ref.vtu");
//   const int field = mesh.chooseField("Temp");
//   uvr::VolumeRenderer renderer(mesh, field);
//   renderer.setTransferFunction(uvr::chooseColorMap("viridis"), mesh.fieldRange(field));
//   uvr::FrameSettings settings;
//   settings.width = settings.height = 512;
//   const uvr::FrameResult frame = renderer.render(uvr::frameBounds(mesh.bounds()), settings);
//   uvr::writePng("out.png", frame.image);
//
// Link the CMake target uvr::uvr (find_package(uvr)). Errors are thrown as uvr::Error.
#pragma once

#include <uvr/camera.h>
#include <uvr/color_map.h>
#include <uvr/error.h>
#include <uvr/gen.h>
#include <uvr/image.h>
#include <uvr/io.h>
#include <uvr/mesh.h>
#include <uvr/renderer.h>
#include <uvr/settings.h>
#include <uvr/system.h>
#include <uvr/vec.h>
