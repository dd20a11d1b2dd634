#include "mpi_group.h"

#include <uvr/settings.h>

#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace uvr {

/// A window of memory that every rank on the node maps: each rank's frame's coloured rectangle, and after
/// rank 0's the composited frame, which each rank lays its band of rows into.
struct MpiGroup::SharedFrames {
  MPI_Win window = MPI_WIN_NULL;
  size_t pixels = 0;            // of the frames it holds
  std::vector<uint16_t *> rgba; // each rank's rectangle
  uint8_t *rgb = nullptr;       // the composited frame, in rank 0's part
  SharedFrames(size_t framePixels, int rank, int ranks) : pixels(framePixels) {
    const MPI_Aint bytes = MPI_Aint(4 * sizeof(uint16_t) * pixels + (rank == 0 ? 3 * pixels : 0));
    void *mine = nullptr;
    MPI_Win_allocate_shared(bytes, 1, MPI_INFO_NULL, MPI_COMM_WORLD, &mine, &window);
    MPI_Win_lock_all(MPI_MODE_NOCHECK, window);
    for (int r = 0; r < ranks; ++r) {
      MPI_Aint size;
      int unit;
      void *base = nullptr;
      MPI_Win_shared_query(window, r, &size, &unit, &base);
      rgba.push_back(static_cast<uint16_t *>(base));
      if (r == 0)
        rgb = static_cast<uint8_t *>(base) + 4 * sizeof(uint16_t) * pixels;
    }
  }
  ~SharedFrames() {
    MPI_Win_unlock_all(window);
    MPI_Win_free(&window);
  }
  /// What every rank wrote before, every rank sees after.
  void fence() {
    MPI_Win_sync(window);
    MPI_Barrier(MPI_COMM_WORLD);
    MPI_Win_sync(window);
  }
};

MpiGroup::MpiGroup() {
  MPI_Init(nullptr, nullptr);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  MPI_Comm node;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &node);
  MPI_Comm_rank(node, &localRank_);
  MPI_Comm_size(node, &nodeSize_);
  MPI_Comm_free(&node);
  const char *how = std::getenv("UVR_MPI_COMPOSITE");
  sharedMemory_ = nodeSize_ == size_ && !(how && std::string(how) == "messages");
}

MpiGroup::~MpiGroup() {
  shared_.reset();
  MPI_Finalize();
}

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
  shared_.reset(); // every rank is here
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

std::vector<std::vector<int64_t>> MpiGroup::allGather(const std::vector<int64_t> &values) {
  std::vector<int> counts(static_cast<size_t>(size_)), offsets(static_cast<size_t>(size_));
  const int count = int(values.size());
  MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  int total = 0;
  for (int r = 0; r < size_; ++r) {
    offsets[size_t(r)] = total;
    total += counts[size_t(r)];
  }
  std::vector<int64_t> all(static_cast<size_t>(total));
  MPI_Allgatherv(values.data(), count, MPI_INT64_T, all.data(), counts.data(), offsets.data(), MPI_INT64_T,
                 MPI_COMM_WORLD);
  std::vector<std::vector<int64_t>> byRank(static_cast<size_t>(size_));
  for (int r = 0; r < size_; ++r)
    byRank[size_t(r)].assign(all.begin() + offsets[size_t(r)],
                             all.begin() + offsets[size_t(r)] + counts[size_t(r)]);
  return byRank;
}

namespace {

/// The box's pixel count.
size_t pixels(const PixelBox &box) { return size_t(box.x1 - box.x0) * size_t(box.y1 - box.y0); }
/// The channels of a row of the box's pixels.
size_t rowChannels(const PixelBox &box) { return 4 * size_t(box.x1 - box.x0); }

/// Runs row(y) for y in [begin, end) on all of this rank's threads: each pass over a frame's image on one
/// core costs about a millisecond.
template <class Row> void forRows(int begin, int end, const Row &row) {
  tbb::parallel_for(tbb::blocked_range<int>(begin, end, 16), [&](const tbb::blocked_range<int> &rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      row(y);
  });
}

/// The smallest rectangle of each band of rows of a premultiplied RGBA image (band b: rows [bands[b],
/// bands[b + 1]), bands[0] = 0) that holds every pixel of non-zero opacity (premultiplied, a pixel without
/// opacity holds no colour), given that none lies outside `colour`; empty where none has.
std::vector<PixelBox> coloredRects(const uint16_t *rgba, int width, const std::vector<int> &bands,
                                   const PixelBox &colour) {
  std::vector<int> first(size_t(bands.back())), last(first.size());
  forRows(0, bands.back(), [&](int y) {
    const uint16_t *row = rgba + size_t(y) * size_t(width) * 4;
    int x0 = colour.x0, x1 = colour.x1;
    if (y < colour.y0 || y >= colour.y1)
      x1 = x0;
    while (x0 < x1 && row[4 * x0 + 3] == 0)
      ++x0;
    while (x1 > x0 && row[4 * (x1 - 1) + 3] == 0)
      --x1;
    first[size_t(y)] = x0;
    last[size_t(y)] = x1;
  });
  std::vector<PixelBox> rects;
  for (size_t b = 0; b + 1 < bands.size(); ++b) {
    PixelBox rect{width, 0, bands[b + 1], bands[b]};
    for (int y = bands[b]; y < bands[b + 1]; ++y) {
      if (first[size_t(y)] < last[size_t(y)])
        rect = {std::min(rect.x0, first[size_t(y)]), std::max(rect.x1, last[size_t(y)]), std::min(rect.y0, y),
                y + 1};
    }
    rects.push_back(rect.y0 < rect.y1 ? rect : PixelBox{0, 0, bands[b], bands[b]});
  }
  return rects;
}

// The ranks' frames come 16 bits a channel (FrameSettings::keepPremultipliedRgba16): a thousandth of what an
// 8-bit image resolves, at a quarter of the bytes of floats.
constexpr float kChannelScale = 65535.f;

uint8_t toByte(float v) { return uint8_t(std::clamp(v, 0.f, 1.f) * 255.f + 0.5f); }

/// Copies the rectangles' pixels of the image (`width` pixels a row) to `out`, rectangle r at offsets[r].
void pack(uint16_t *out, const uint16_t *rgba, int width, const std::vector<PixelBox> &rects,
          const std::vector<int> &offsets) {
  for (size_t r = 0; r < rects.size(); ++r) {
    const PixelBox &rect = rects[r];
    forRows(rect.y0, rect.y1, [&](int y) {
      const uint16_t *from = rgba + (size_t(y) * size_t(width) + size_t(rect.x0)) * 4;
      std::copy(from, from + rowChannels(rect), out + offsets[r] + size_t(y - rect.y0) * rowChannels(rect));
    });
  }
}

/// A rank's coloured rectangle: its pixels' 4 channels, row after row.
struct Layer {
  PixelBox rect;
  const uint16_t *rgba;
};

/// Composites the layers (front first) over rows [box.y0, box.y1) and columns [box.x0, box.x1) of the frame
/// (outside which none has colour), over the background `under` into 8-bit RGB: `out` is the box's corner,
/// `outStride` bytes a row. `scratch` holds a float row a row of the box.
void compositeBox(const std::vector<Layer> &layers, const PixelBox &box, const float under[3],
                  std::vector<float> &scratch, uint8_t *out, size_t outStride) {
  scratch.resize(4 * pixels(box));
  forRows(box.y0, box.y1, [&](int y) {
    float *row = scratch.data() + size_t(y - box.y0) * rowChannels(box);
    std::fill(row, row + rowChannels(box), 0.f);
    for (const Layer &layer : layers) {
      const PixelBox &rect = layer.rect;
      if (y < rect.y0 || y >= rect.y1)
        continue;
      const uint16_t *from = layer.rgba + size_t(y - rect.y0) * rowChannels(rect);
      for (float *pixel = row + 4 * size_t(rect.x0 - box.x0), *end = row + 4 * size_t(rect.x1 - box.x0);
           pixel != end; pixel += 4, from += 4) {
        // A ray stops once kTerminationOpacity opaque, the light it would still let through given the colour
        // of what it last went through (compositeBehind): so does the composite, at a region's colour.
        if (pixel[3] >= kTerminationOpacity || from[3] == 0)
          continue;
        float through = (1.f - pixel[3]) / kChannelScale;
        if (pixel[3] + through * float(from[3]) >= kTerminationOpacity)
          through = (1.f - pixel[3]) / float(from[3]);
        for (int c = 0; c < 4; ++c)
          pixel[c] += through * float(from[c]);
      }
    }
    uint8_t *to = out + size_t(y - box.y0) * outStride;
    for (const float *from = row, *end = row + rowChannels(box); from != end; from += 4, to += 3)
      for (int c = 0; c < 3; ++c)
        to[c] = toByte(from[c] + (1.f - from[3]) * under[c]);
  });
}

/// Lays the background over each row of [y0, y1) of a `width`-pixel RGB frame outside [x0[y], x1[y]).
void layBackground(uint8_t *frame, int width, int y0, int y1, const std::vector<int> &x0,
                   const std::vector<int> &x1, const std::vector<uint8_t> &backgroundRow) {
  forRows(y0, y1, [&](int y) {
    uint8_t *row = frame + 3 * size_t(y) * size_t(width);
    const size_t left = size_t(x0[size_t(y)]), right = size_t(x1[size_t(y)]);
    std::copy(backgroundRow.data(), backgroundRow.data() + 3 * left, row);
    std::copy(backgroundRow.data() + 3 * right, backgroundRow.data() + 3 * size_t(width), row + 3 * right);
  });
}

/// A background row of `width` pixels, 8 bits a channel, rounded as a single process's frame is.
std::vector<uint8_t> backgroundRowOf(Vec3f background, int width) {
  const float under[3] = {background.x, background.y, background.z};
  std::vector<uint8_t> row(3 * size_t(width));
  for (size_t i = 0; i < row.size(); ++i)
    row[i] = toByte(under[i % 3]);
  return row;
}

} // namespace

uint64_t MpiGroup::composite(const std::vector<uint16_t> &rgba, int width, int height,
                             const std::vector<int> &order, const PixelBox &colour, Vec3f background,
                             Image &image) {
  // Rank r composites rows [bands[r], bands[r + 1]).
  std::vector<int> bands;
  for (int r = 0; r <= size_; ++r)
    bands.push_back(int(int64_t(height) * r / size_));
  const size_t ranks = size_t(size_);
  const int bandBegin = bands[size_t(rank_)], bandEnd = bands[size_t(rank_) + 1];
  const float under[3] = {background.x, background.y, background.z};
  const std::vector<uint8_t> backgroundRow = backgroundRowOf(background, width);
  if (rank_ == 0) {
    image.width = width;
    image.height = height;
    image.rgb.resize(3 * size_t(width) * size_t(height));
  }
  static_assert(sizeof(PixelBox) == 4 * sizeof(int));
  // An empty rectangle, or one clipped to nothing (its far edge before its near one), widens nothing.
  const auto unite = [](PixelBox box, const PixelBox &rect) {
    return !(rect.x0 < rect.x1 && rect.y0 < rect.y1)
               ? box
               : PixelBox{std::min(box.x0, rect.x0), std::max(box.x1, rect.x1), std::min(box.y0, rect.y0),
                          std::max(box.y1, rect.y1)};
  };

  if (sharedMemory_) {
    // All ranks on one node: each lays its coloured rectangle in the shared window, and each composites its
    // band from all of them, in place, into rank 0's frame there. Nothing is sent.
    const size_t framePixels = size_t(width) * size_t(height);
    if (!shared_ || shared_->pixels != framePixels)
      shared_ = std::make_unique<SharedFrames>(framePixels, rank_, size_);
    const PixelBox rect = coloredRects(rgba.data(), width, {0, height}, colour)[0];
    pack(shared_->rgba[size_t(rank_)], rgba.data(), width, {rect}, {0});
    std::vector<PixelBox> rects(ranks);
    MPI_Allgather(&rect, 4, MPI_INT, rects.data(), 4, MPI_INT, MPI_COMM_WORLD);
    shared_->fence();
    std::vector<Layer> layers;
    PixelBox box{width, 0, bandEnd, bandBegin};
    for (const int r : order) {
      const PixelBox &theirs = rects[size_t(r)];
      layers.push_back({theirs, shared_->rgba[size_t(r)]});
      box = unite(box, {theirs.x0, theirs.x1, std::max(theirs.y0, bandBegin), std::min(theirs.y1, bandEnd)});
    }
    if (!(box.y0 < box.y1))
      box = {0, 0, bandBegin, bandBegin};
    compositeBox(layers, box, under, band_,
                 shared_->rgb + 3 * (size_t(box.y0) * size_t(width) + size_t(box.x0)), 3 * size_t(width));
    std::vector<int> rowX0(size_t(height), width), rowX1(size_t(height), width);
    for (int y = box.y0; y < box.y1; ++y) {
      rowX0[size_t(y)] = box.x0;
      rowX1[size_t(y)] = box.x1;
    }
    layBackground(shared_->rgb, width, bandBegin, bandEnd, rowX0, rowX1, backgroundRow);
    shared_->fence();
    if (rank_ == 0)
      forRows(0, height, [&](int y) {
        const uint8_t *row = shared_->rgb + 3 * size_t(y) * size_t(width);
        std::copy(row, row + 3 * size_t(width), image.rgb.data() + 3 * size_t(y) * size_t(width));
      });
    shared_->fence(); // no rank writes the next frame's rectangle before rank 0 has this one
    // What crossed between ranks: this rank's rectangle outside its band, and its band for rank 0.
    uint64_t crossed = 0;
    for (int y = rect.y0; y < rect.y1; ++y)
      crossed += (y < bandBegin || y >= bandEnd) ? 4 * sizeof(uint16_t) * size_t(rect.x1 - rect.x0) : 0;
    return crossed + (rank_ == 0 ? 0 : 3 * size_t(width) * size_t(bandEnd - bandBegin));
  }

  // Each band's coloured rectangle to the rank that composites it, the rectangles first.
  const std::vector<PixelBox> sentRects = coloredRects(rgba.data(), width, bands, colour);
  std::vector<PixelBox> receivedRects(ranks);
  std::vector<int> sendCounts(ranks), sendOffsets(ranks), receiveCounts(ranks), receiveOffsets(ranks);
  int sentTotal = 0, receivedTotal = 0;
  uint64_t sentBytes = 0;
  for (size_t r = 0; r < ranks; ++r) {
    sendOffsets[r] = sentTotal;
    sendCounts[r] = int(4 * pixels(sentRects[r]));
    sentTotal += sendCounts[r];
    if (int(r) != rank_)
      sentBytes += uint64_t(sendCounts[r]) * sizeof(uint16_t);
  }
  sent_.resize(size_t(sentTotal));
  pack(sent_.data(), rgba.data(), width, sentRects, sendOffsets);
  MPI_Alltoall(sentRects.data(), 4, MPI_INT, receivedRects.data(), 4, MPI_INT, MPI_COMM_WORLD);
  for (size_t r = 0; r < ranks; ++r) {
    receiveOffsets[r] = receivedTotal;
    receiveCounts[r] = int(4 * pixels(receivedRects[r]));
    receivedTotal += receiveCounts[r];
  }
  received_.resize(size_t(receivedTotal));
  MPI_Alltoallv(sent_.data(), sendCounts.data(), sendOffsets.data(), MPI_UINT16_T, received_.data(),
                receiveCounts.data(), receiveOffsets.data(), MPI_UINT16_T, MPI_COMM_WORLD);

  // Front to back: each region's colour behind what the regions before it let through, over the rectangle
  // that holds all they sent, and over the background; rank 0 lays its band straight into the frame, the
  // others into what they send it.
  std::vector<Layer> layers;
  PixelBox mine{width, 0, bandEnd, bandBegin};
  for (const int r : order) {
    layers.push_back({receivedRects[size_t(r)], received_.data() + receiveOffsets[size_t(r)]});
    mine = unite(mine, receivedRects[size_t(r)]);
  }
  if (!(mine.y0 < mine.y1))
    mine = {0, 0, bandBegin, bandBegin};
  if (rank_ == 0) {
    compositeBox(layers, mine, under, band_,
                 image.rgb.data() + 3 * (size_t(mine.y0) * size_t(width) + size_t(mine.x0)),
                 3 * size_t(width));
  } else {
    bandRgb_.resize(3 * pixels(mine));
    compositeBox(layers, mine, under, band_, bandRgb_.data(), 3 * size_t(mine.x1 - mine.x0));
  }

  // The composited bands' rectangles to rank 0, received straight into their place in the frame while it
  // lays the background around them.
  constexpr int kBandTag = 1;
  std::vector<PixelBox> bandRects(rank_ == 0 ? ranks : 0);
  MPI_Gather(&mine, 4, MPI_INT, bandRects.data(), 4, MPI_INT, 0, MPI_COMM_WORLD);
  if (rank_ != 0) {
    if (!bandRgb_.empty())
      MPI_Send(bandRgb_.data(), int(bandRgb_.size()), MPI_UINT8_T, 0, kBandTag, MPI_COMM_WORLD);
    return sentBytes + bandRgb_.size();
  }
  std::vector<MPI_Request> requests;
  for (size_t r = 1; r < ranks; ++r) {
    const PixelBox &rect = bandRects[r];
    if (pixels(rect) == 0)
      continue;
    MPI_Datatype rows;
    MPI_Type_vector(rect.y1 - rect.y0, 3 * (rect.x1 - rect.x0), 3 * width, MPI_UINT8_T, &rows);
    MPI_Type_commit(&rows);
    requests.emplace_back();
    MPI_Irecv(image.rgb.data() + 3 * (size_t(rect.y0) * size_t(width) + size_t(rect.x0)), 1, rows, int(r),
              kBandTag, MPI_COMM_WORLD, &requests.back());
    MPI_Type_free(&rows); // freed once the receive completes
  }
  std::vector<int> rowX0(size_t(height), width), rowX1(size_t(height), width); // each row's composited pixels
  for (const PixelBox &rect : bandRects)
    for (int y = rect.y0; y < rect.y1; ++y) {
      rowX0[size_t(y)] = rect.x0;
      rowX1[size_t(y)] = rect.x1;
    }
  layBackground(image.rgb.data(), width, 0, height, rowX0, rowX1, backgroundRow);
  MPI_Waitall(int(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
  return sentBytes;
}

} // namespace uvr
