#include "mpi_group.h"

#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>

namespace uvr {

MpiGroup::MpiGroup() {
  MPI_Init(nullptr, nullptr);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  MPI_Comm node;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &node);
  MPI_Comm_rank(node, &localRank_);
  MPI_Comm_free(&node);
}

MpiGroup::~MpiGroup() { MPI_Finalize(); }

void MpiGroup::step(const std::function<void()> &work) {
  std::string error;
  try {
    work();
  } catch (const std::bad_alloc &) {
    error = "out of memory";
  } catch (const std::exception &e) {
    error = e.what();
    if (error.empty())
      error = "failed";
  }
  int failed = error.empty() ? size_ : rank_;
  MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (failed == size_)
    return;
  int length = int(error.size());
  MPI_Bcast(&length, 1, MPI_INT, failed, MPI_COMM_WORLD);
  error.resize(size_t(length));
  MPI_Bcast(error.data(), length, MPI_CHAR, failed, MPI_COMM_WORLD);
  if (rank_ == 0) {
    std::fprintf(stderr, "uvr: error: rank %d: %s\n", failed, error.c_str());
    std::fflush(stderr);
  }
  MPI_Finalize();
  std::exit(2);
}

void MpiGroup::barrier() { MPI_Barrier(MPI_COMM_WORLD); }

double MpiGroup::maxOf(double value) {
  MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return value;
}

uint64_t MpiGroup::sumOf(uint64_t value) {
  MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  return value;
}

std::vector<double> MpiGroup::gather(double value) {
  std::vector<double> all(rank_ == 0 ? size_t(size_) : 0);
  MPI_Gather(&value, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  return all;
}

std::vector<uint32_t> MpiGroup::sum(const std::vector<uint32_t> &values) {
  std::vector<uint32_t> total(rank_ == 0 ? values.size() : 0);
  MPI_Reduce(values.data(), total.data(), int(values.size()), MPI_UINT32_T, MPI_SUM, 0, MPI_COMM_WORLD);
  return total;
}

uint64_t MpiGroup::composite(std::vector<float> &rgba, int width, int height, const std::vector<int> &order) {
  // Rank r composites rows [band[r], band[r + 1]).
  const auto band = [&](int r) { return int(int64_t(height) * r / size_); };
  const int rowFloats = 4 * width;
  const size_t ranks = size_t(size_);
  std::vector<int> sendCounts(ranks), sendOffsets(ranks), receiveCounts(ranks), receiveOffsets(ranks);
  const int myRows = band(rank_ + 1) - band(rank_);
  for (int r = 0; r < size_; ++r) {
    sendCounts[size_t(r)] = (band(r + 1) - band(r)) * rowFloats;
    sendOffsets[size_t(r)] = band(r) * rowFloats;
    receiveCounts[size_t(r)] = myRows * rowFloats;
    receiveOffsets[size_t(r)] = r * myRows * rowFloats;
  }
  std::vector<float> received(size_t(size_) * size_t(myRows) * size_t(rowFloats));
  MPI_Alltoallv(rgba.data(), sendCounts.data(), sendOffsets.data(), MPI_FLOAT, received.data(),
                receiveCounts.data(), receiveOffsets.data(), MPI_FLOAT, MPI_COMM_WORLD);
  uint64_t sent = 0;
  for (int r = 0; r < size_; ++r)
    if (r != rank_)
      sent += uint64_t(sendCounts[size_t(r)]) * sizeof(float);

  // Front to back: each region's colour behind what the regions before it let through.
  const size_t bandFloats = size_t(myRows) * size_t(rowFloats);
  std::vector<float> composited(bandFloats, 0.f);
  for (const int r : order) {
    const float *layer = received.data() + size_t(r) * bandFloats;
    for (size_t i = 0; i < bandFloats; i += 4) {
      // A ray stops once this opaque (the renderer's early termination): so does the composite, else the
      // regions behind would add what a single process leaves out.
      constexpr float kTerminationOpacity = 0.99f;
      if (composited[i + 3] >= kTerminationOpacity)
        continue;
      const float through = 1.f - composited[i + 3];
      for (size_t c = 0; c < 4; ++c)
        composited[i + c] += through * layer[i + c];
    }
  }

  for (int r = 0; r < size_; ++r) {
    receiveCounts[size_t(r)] = (band(r + 1) - band(r)) * rowFloats;
    receiveOffsets[size_t(r)] = band(r) * rowFloats;
  }
  if (rank_ == 0)
    rgba.assign(size_t(height) * size_t(rowFloats), 0.f);
  MPI_Gatherv(composited.data(), int(bandFloats), MPI_FLOAT, rgba.data(), receiveCounts.data(),
              receiveOffsets.data(), MPI_FLOAT, 0, MPI_COMM_WORLD);
  if (rank_ != 0)
    sent += bandFloats * sizeof(float);
  return sent;
}

} // namespace uvr
