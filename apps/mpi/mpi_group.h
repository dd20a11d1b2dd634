// The ranks of an MPI run (mpirun -np N uvr ...), as the command uses them: started only where a launcher
// started this process, every fallible step agreed on by all ranks, and the images composited. The header
// holds no MPI type, so that the command compiles the same with or without MPI.
#pragma once

#include <uvr/camera.h>
#include <uvr/image.h>

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace uvr {

/// Whether an MPI launcher (mpirun, mpiexec, srun) started this process among several: read from the
/// environment (Open MPI's, PMI's and PMIx's), so that a plain run neither needs nor starts MPI.
inline bool startedByMpiLauncher() {
  for (const char *name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"}) {
    const char *value = std::getenv(name);
    if (value && std::atoi(value) > 1)
      return true;
  }
  return false;
}

class MpiGroup {
public:
  /// MPI_Init; MPI_Finalize on destruction.
  MpiGroup();
  ~MpiGroup();
  MpiGroup(const MpiGroup &) = delete;
  MpiGroup &operator=(const MpiGroup &) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  /// The rank among those on this node: which GPU it takes.
  int localRank() const { return localRank_; }
  /// The ranks on this node: they share its cores.
  int nodeSize() const { return nodeSize_; }

  /// Runs `work` on every rank, then agrees on its success: where it threw on any rank, rank 0 prints the
  /// lowest such rank's message and every rank ends with status 2 (no rank is left waiting).
  void step(const std::function<void()> &work);

  void barrier();
  double maxOf(double value);
  uint64_t sumOf(uint64_t value);
  /// Every rank's value, at rank 0 (empty elsewhere).
  std::vector<double> gather(double value);
  /// The element-wise sums of every rank's `values` (all of one length), at rank 0 (empty elsewhere).
  std::vector<uint32_t> sum(const std::vector<uint32_t> &values);
  /// Every rank's `values` (of any length), by rank, on every rank.
  std::vector<std::vector<int64_t>> allGather(const std::vector<int64_t> &values);

  /// Composites every rank's premultiplied RGBA image (`width` x `height`, 4 channels a pixel, 65535 for 1,
  /// as FrameSettings::keepPremultipliedRgba16 gives it) front to back in `order` (ranks, front first) into
  /// `image` at rank 0: each rank composites a band of rows from every rank's part of it (this rank's image
  /// has colour only inside `colour`) and lays it over `background`. Where all ranks share a node, through a
  /// window of memory they all map; otherwise by direct send, the rectangle of each band that holds colour
  /// to the band's rank, 16 bits a channel, and each band to rank 0, 8-bit RGB. Returns the bytes this rank
  /// passed to others.
  uint64_t composite(const std::vector<uint16_t> &rgba, int width, int height, const std::vector<int> &order,
                     const PixelBox &colour, Vec3f background, Image &image);

private:
  struct SharedFrames;

  int rank_ = 0, size_ = 1, localRank_ = 0, nodeSize_ = 1;
  /// Whether the ranks composite through memory they all map (all on one node; UVR_MPI_COMPOSITE=messages
  /// in the environment says no) rather than by messages.
  bool sharedMemory_ = false;
  std::unique_ptr<SharedFrames> shared_;
  // The composite's buffers, kept across frames: fresh pages each frame cost more than the copies.
  std::vector<uint16_t> sent_, received_;
  std::vector<float> band_;
  std::vector<uint8_t> bandRgb_;
};

} // namespace uvr
