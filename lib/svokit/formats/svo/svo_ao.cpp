// The `AOCC` section of a version-2 .svo (formats/svo.md, "Ambient occlusion"): one byte of baked
// ambient occlusion per node of every level, in node order, zstd-compressed as one stream.

#include <cstring>

#include <zstd.h>

#include "svokit/core/bytes.hpp"
#include "svokit/core/release_pages.hpp"
#include "svokit/formats/svo/svo_detail.hpp"

namespace svokit {

namespace svo_detail {

namespace {

constexpr std::uint32_t kStored = 0, kZstd = 1;
constexpr std::size_t kAoHeader = 24;

// The first out.size() bytes a zstd frame decodes to.
bool DecompressPrefix(std::span<const std::uint8_t> frame, std::span<std::uint8_t> out) {
  ZSTD_DCtx* ctx = ZSTD_createDCtx();
  ZSTD_inBuffer in{frame.data(), frame.size(), 0};
  ZSTD_outBuffer to{out.data(), out.size(), 0};
  bool ok = true;
  while (to.pos < to.size) {
    const std::size_t in_before = in.pos, out_before = to.pos;
    const std::size_t r = ZSTD_decompressStream(ctx, &to, &in);
    if (ZSTD_isError(r) || r == 0 || (in.pos == in_before && to.pos == out_before)) {
      ok = !ZSTD_isError(r) && to.pos == to.size;
      break;
    }
  }
  ZSTD_freeDCtx(ctx);
  return ok && to.pos == to.size;
}

}  // namespace

std::vector<std::uint8_t> EncodeAoSection(std::span<const std::vector<std::uint8_t>> ao) {
  std::uint64_t raw = 0;
  for (const std::vector<std::uint8_t>& level : ao) raw += level.size();
  // Header: levels and codec (two u32; GCC 12 misreads four scalar appends as an overflow), the
  // raw and stored sizes (two u64, the stored one written once known), then the stream.
  const auto put_header = [&](ByteWriter& bytes, std::uint32_t codec, std::uint64_t stored) {
    const std::uint32_t head[2] = {static_cast<std::uint32_t>(ao.size()), codec};
    const std::uint64_t sizes[2] = {raw, stored};
    bytes.PutArray(std::span<const std::uint32_t>(head));
    bytes.PutArray(std::span<const std::uint64_t>(sizes));
  };
  ByteWriter bytes;
  put_header(bytes, kZstd, 0);
  std::vector<std::uint8_t>& out = bytes.bytes();
  const std::size_t header = out.size();
  // The levels compressed as one frame, fed level by level and drained a piece at a time: what is
  // held is the compressed bytes, not a buffer of ZSTD_compressBound(raw).
  std::vector<std::uint8_t> piece(std::size_t{1} << 20);
  ZSTD_CCtx* ctx = ZSTD_createCCtx();
  ZSTD_CCtx_setParameter(ctx, ZSTD_c_compressionLevel, 9);
  ZSTD_CCtx_setPledgedSrcSize(ctx, raw);
  bool zstd = true;
  for (std::size_t l = 0; zstd && l <= ao.size(); ++l) {
    const bool last = l == ao.size();
    ZSTD_inBuffer in{last ? nullptr : ao[l].data(), last ? 0 : ao[l].size(), 0};
    std::size_t left = 0;
    do {
      ZSTD_outBuffer to{piece.data(), piece.size(), 0};
      left = ZSTD_compressStream2(ctx, &to, &in, last ? ZSTD_e_end : ZSTD_e_continue);
      zstd = !ZSTD_isError(left);
      out.insert(out.end(), piece.begin(), piece.begin() + static_cast<std::ptrdiff_t>(to.pos));
      zstd = zstd && out.size() - header < raw;  // stored raw when zstd does not shrink it
    } while (zstd && (last ? left != 0 : in.pos < in.size));
  }
  ZSTD_freeCCtx(ctx);
  if (zstd) {
    const std::uint64_t stored = out.size() - header;
    std::memcpy(out.data() + header - sizeof stored, &stored, sizeof stored);
    return std::move(out);
  }
  ByteWriter plain;
  put_header(plain, kStored, raw);
  for (const std::vector<std::uint8_t>& level : ao) {
    plain.PutArray(std::span<const std::uint8_t>(level));
  }
  return std::move(plain.bytes());
}

namespace {

// The checks of DecodeAo that need only the node counts: the header, and the raw size against
// `nodes` (the first `nodes` bytes when `whole` is false). The section's payload when they hold.
std::optional<std::pair<std::span<const std::uint8_t>, std::uint64_t>> CheckAoHeader(
    std::span<const std::uint8_t> section, const std::string& name, std::uint32_t depth,
    std::uint64_t nodes, bool whole, IssueSink& sink, std::uint32_t& codec) {
  ByteReader in(section, name + ": AOCC");
  std::uint32_t levels = 0;
  std::uint64_t raw = 0, stored = 0;
  if (!in.Get(levels).ok() || !in.Get(codec).ok() || !in.Get(raw).ok() || !in.Get(stored).ok()) {
    sink.Add("ao", name, "the AOCC section is shorter than its header");
    return std::nullopt;
  }
  if (levels != depth + 1 || (codec != kStored && codec != kZstd) ||
      stored != section.size() - kAoHeader || (codec == kStored && stored != raw)) {
    sink.Add("ao", name, "the AOCC section's header is inconsistent ({} levels, codec {})", levels,
             codec);
    return std::nullopt;
  }
  if (whole ? raw != nodes : raw < nodes) {
    sink.Add("ao", name, "the AOCC section holds {} bytes for {} nodes", raw, nodes);
    return std::nullopt;
  }
  return std::pair{section.subspan(kAoHeader, stored), raw};
}

}  // namespace

bool DecodeAo(const container::Frame& file, std::uint32_t last, IssueSink& sink, Svo& svo) {
  const std::optional<std::span<const std::uint8_t>> section = Loaded(file, kAo);
  if (!section) return true;
  const std::string& name = file.name();
  // Levels past `last` were not decoded: their bytes follow the decoded levels' and are dropped.
  std::uint64_t nodes = 0;
  for (std::uint32_t l = 0; l <= last && l < svo.levels.size(); ++l)
    nodes += svo.levels[l].node_count;
  // A whole octree needs every byte; one read down to `last` the first `nodes` (levels in order).
  std::uint32_t codec = 0;
  const auto payload =
      CheckAoHeader(*section, name, svo.depth, nodes, last >= svo.depth, sink, codec);
  if (!payload) return false;
  const auto [p, raw] = *payload;
  std::vector<std::uint8_t> bytes(nodes);
  if (codec == kStored) {
    std::copy(p.begin(), p.begin() + static_cast<std::ptrdiff_t>(nodes), bytes.begin());
  } else if (ZSTD_getFrameContentSize(p.data(), p.size()) != raw || !DecompressPrefix(p, bytes)) {
    sink.Add("ao", name, "the AOCC stream does not decode to its {} bytes", raw);
    return false;
  }
  std::uint64_t at = 0;
  for (SvoLevel& level : svo.levels) {
    level.ao.assign(bytes.begin() + static_cast<std::ptrdiff_t>(at),
                    bytes.begin() + static_cast<std::ptrdiff_t>(at + level.node_count));
    at += level.node_count;
  }
  svo.has_ao = true;
  return true;
}

bool ReadAoRange(const container::Frame& file, std::uint32_t depth, std::uint64_t nodes,
                 std::uint64_t first, std::span<std::uint8_t> out, IssueSink& sink) {
  const std::optional<std::span<const std::uint8_t>> section = Loaded(file, kAo);
  if (!section) return true;
  const std::string& name = file.name();
  std::uint32_t codec = 0;
  const auto payload = CheckAoHeader(*section, name, depth, nodes, true, sink, codec);
  if (!payload) return false;
  const auto [p, raw] = *payload;
  if (first + out.size() > raw) {
    sink.Add("ao", name, "the AOCC section holds no bytes {} to {}", first, first + out.size());
    return false;
  }
  if (codec == kStored) {
    std::copy_n(p.begin() + static_cast<std::ptrdiff_t>(first), out.size(), out.begin());
    return true;
  }
  // Decoded through a small buffer, the range kept: the stream's length is what DecodeAo checks.
  bool ok = ZSTD_getFrameContentSize(p.data(), p.size()) == raw;
  ZSTD_DCtx* ctx = ZSTD_createDCtx();
  std::vector<std::uint8_t> buffer(std::size_t{1} << 20);
  ZSTD_inBuffer in{p.data(), p.size(), 0};
  std::uint64_t at = 0;
  while (ok && at < raw) {
    ZSTD_outBuffer to{buffer.data(), std::min<std::uint64_t>(buffer.size(), raw - at), 0};
    const std::size_t in_before = in.pos;
    const std::size_t r = ZSTD_decompressStream(ctx, &to, &in);
    // The part of [first, first + out.size()) this piece of the stream holds.
    const std::uint64_t lo = std::max(at, first), hi = std::min(at + to.pos, first + out.size());
    if (lo < hi) std::copy_n(buffer.begin() + (lo - at), hi - lo, out.begin() + (lo - first));
    at += to.pos;
    if (ZSTD_isError(r) || (r == 0 && at < raw) || (in.pos == in_before && to.pos == 0)) {
      ok = !ZSTD_isError(r) && at == raw;
    }
  }
  ZSTD_freeDCtx(ctx);
  if (!ok) sink.Add("ao", name, "the AOCC stream does not decode to its {} bytes", raw);
  return ok;
}

bool CheckAo(const container::Frame& file, std::uint32_t depth, std::uint64_t nodes,
             IssueSink& sink) {
  return ReadAoRange(file, depth, nodes, 0, {}, sink);
}

}  // namespace svo_detail

Status WriteBakedSvo(const std::filesystem::path& input,
                     std::span<const std::vector<std::uint8_t>> ao, const BakeSettings& bake,
                     const std::filesystem::path& output) {
  using namespace svo_detail;
  // The pages are not read here: each is checked where it is decoded (by the bake that traced it).
  static constexpr std::uint32_t kAllLevels = ~0u;
  StatusOr<container::Frame> frame =
      container::Frame::Open(input, kSvoFormat, &SectionsToLoad, &kAllLevels);
  if (!frame.ok()) return frame.status();
  if (!frame->issues().empty()) return Status::BadInput("{}", frame->issues().front().message);
  if (frame->version() < 2) {
    return Status::BadInput("{}: a version-{} file; rebuild it to bake into it", input.string(),
                            frame->version());
  }
  Provenance provenance;
  if (const container::Frame::Section* m = frame->Find(kMetadata)) {
    provenance = ParseProvenance(
        std::string_view(reinterpret_cast<const char*>(m->bytes.data()), m->bytes.size()));
  }
  provenance.bake = bake;
  const std::string meta_text = ProvenanceJson(provenance);

  // The input's version: the bricks keep the filter they were made by.
  container::FormatId format = kSvoFormat;
  format.version = frame->version();
  container::Writer writer(format, frame->flags());
  for (const container::Frame::Section& s : frame->sections()) {
    if (s.tag == kAo || s.tag == kMetadata) continue;
    writer.AddSectionProduced(s.tag, [bytes = s.bytes](const container::Writer::Emit& emit) {
      constexpr std::size_t kPiece = std::size_t{8} << 20;
      for (std::size_t at = 0; at < bytes.size(); at += kPiece) {
        const std::span<const std::uint8_t> piece =
            bytes.subspan(at, std::min(kPiece, bytes.size() - at));
        SVOKIT_RETURN_IF_ERROR(emit(piece));
        ReleaseMappedFilePages(piece.data(), piece.data() + piece.size());
      }
      return Status::Ok();
    });
  }
  writer.AddSection(kMetadata, std::vector<std::uint8_t>(meta_text.begin(), meta_text.end()));
  writer.AddSection(kAo, EncodeAoSection(ao));
  return writer.WriteFile(output);
}

}  // namespace svokit
