// One group of pictures through libavcodec, for bench_spatial_video: a run of
// RGBA frames coded as one closed, self-contained video stream (its own
// encoder: keyframe first, then P/B frames; in-band headers, no container),
// and that stream decoded on one thread with the time at which each frame is
// ready (decoded from the keyframe on, converted back to RGBA) -- the cost of
// decoding that frame alone by random access. Colour: full-range BT.601 YUV
// 4:4:4 via libswscale, as libavif codes the bake's AVIF faces.
// Every libav* call is checked; a failure throws std::runtime_error naming it.
// Header-only; needs libavcodec, libavutil, libswscale.
#pragma once

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/error.h>
#include <libavutil/frame.h>
#include <libavutil/opt.h>
#include <libavutil/pixdesc.h>
#include <libswscale/swscale.h>
}

#include <chrono>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "stages/geometry.h"

namespace cellbake::video {

inline std::string av_error(int code) {
  char buf[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, buf, sizeof buf);
  return buf;
}

// Throws when a libav* call returned a negative code.
inline int check(int ret, const std::string& what) {
  if (ret < 0) throw std::runtime_error(what + ": " + av_error(ret));
  return ret;
}

struct CodecContextFree {
  void operator()(AVCodecContext* p) const { avcodec_free_context(&p); }
};
struct FrameFree {
  void operator()(AVFrame* p) const { av_frame_free(&p); }
};
struct PacketFree {
  void operator()(AVPacket* p) const { av_packet_free(&p); }
};
struct SwsFree {
  void operator()(SwsContext* p) const { sws_freeContext(p); }
};
using CodecContextPtr = std::unique_ptr<AVCodecContext, CodecContextFree>;
using FramePtr = std::unique_ptr<AVFrame, FrameFree>;
using PacketPtr = std::unique_ptr<AVPacket, PacketFree>;
using SwsPtr = std::unique_ptr<SwsContext, SwsFree>;

inline FramePtr make_frame() {
  FramePtr f(av_frame_alloc());
  if (!f) throw std::runtime_error("av_frame_alloc failed");
  return f;
}
inline PacketPtr make_packet() {
  PacketPtr p(av_packet_alloc());
  if (!p) throw std::runtime_error("av_packet_alloc failed");
  return p;
}

// RGBA8 <-> YUV 4:4:4 8-bit, full range, BT.601 matrix (libavif's default).
class ColourConverter {
 public:
  ColourConverter(int size, bool to_yuv) : size_(size) {
    const AVPixelFormat rgba = AV_PIX_FMT_RGBA, yuv = AV_PIX_FMT_YUV444P;
    const int flags = SWS_POINT | SWS_ACCURATE_RND | SWS_FULL_CHR_H_INT | SWS_FULL_CHR_H_INP;
    ctx_.reset(sws_getContext(size, size, to_yuv ? rgba : yuv, size, size, to_yuv ? yuv : rgba, flags, nullptr,
                              nullptr, nullptr));
    if (!ctx_) throw std::runtime_error("sws_getContext failed (RGBA <-> yuv444p)");
    const int* bt601 = sws_getCoefficients(SWS_CS_ITU601);
    check(sws_setColorspaceDetails(ctx_.get(), bt601, 1, bt601, 1, 0, 1 << 16, 1 << 16),
          "sws_setColorspaceDetails");
  }
  // `rgba` (size^2 pixels) into `frame` (allocated yuv444p, size^2).
  void to_yuv(const std::vector<Rgba8>& rgba, AVFrame& frame) const {
    const std::uint8_t* src[4] = {reinterpret_cast<const std::uint8_t*>(rgba.data()), nullptr, nullptr, nullptr};
    const int stride[4] = {size_ * 4, 0, 0, 0};
    check(sws_scale(ctx_.get(), src, stride, 0, size_, frame.data, frame.linesize), "sws_scale to yuv444p");
  }
  std::vector<Rgba8> to_rgba(const AVFrame& frame) const {
    if (frame.format != AV_PIX_FMT_YUV444P || frame.width != size_ || frame.height != size_)
      throw std::runtime_error(std::string("decoded frame is ") + av_get_pix_fmt_name(AVPixelFormat(frame.format)) +
                               " " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                               ", expected yuv444p " + std::to_string(size_) + "^2");
    std::vector<Rgba8> out(std::size_t(size_) * std::size_t(size_));
    std::uint8_t* dst[4] = {reinterpret_cast<std::uint8_t*>(out.data()), nullptr, nullptr, nullptr};
    const int stride[4] = {size_ * 4, 0, 0, 0};
    check(sws_scale(ctx_.get(), frame.data, frame.linesize, 0, size_, dst, stride), "sws_scale to RGBA");
    return out;
  }

 private:
  int size_;
  SwsPtr ctx_;
};

struct EncoderParams {
  std::string encoder;  // "libaom-av1" | "libx265"
  double crf = 30;      // constant-quality level (aom: cq-level 0..63; x265: crf 0..51)
  int aom_cpu_used = 6; // libaom-av1 speed
  std::string aom_usage = "good";
  std::string x265_preset = "medium";
};

struct StreamPacket {
  std::vector<std::uint8_t> data;
  std::int64_t pts = 0, dts = 0;
  int flags = 0;
};

struct EncodedGroup {
  std::vector<StreamPacket> packets;
  std::size_t bytes = 0;
  int frames = 0;
  double encode_ms = 0;  // encoder set-up, colour conversion, coding, flush
};

inline double ms_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// Codes `frames` (each size^2 RGBA) as one stream: a fresh encoder on one
// thread, keyframe first, GOP = the group, then flushed.
inline EncodedGroup encode_group(const std::vector<const std::vector<Rgba8>*>& frames, int size,
                                 const EncoderParams& p) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const AVCodec* codec = avcodec_find_encoder_by_name(p.encoder.c_str());
  if (!codec) throw std::runtime_error("libavcodec has no encoder '" + p.encoder + "'");
  CodecContextPtr c(avcodec_alloc_context3(codec));
  if (!c) throw std::runtime_error("avcodec_alloc_context3 failed");
  const int n = int(frames.size());
  c->width = c->height = size;
  c->pix_fmt = AV_PIX_FMT_YUV444P;
  c->color_range = AVCOL_RANGE_JPEG;
  c->colorspace = AVCOL_SPC_BT470BG;
  c->time_base = {1, 25};
  c->framerate = {25, 1};
  c->gop_size = n;
  c->keyint_min = n;
  c->thread_count = 1;
  c->bit_rate = 0;
  const std::string enc = "encoder " + p.encoder;
  if (p.encoder == "libaom-av1") {
    check(av_opt_set_int(c->priv_data, "crf", std::int64_t(p.crf), 0), enc + ": option crf");
    check(av_opt_set_int(c->priv_data, "cpu-used", p.aom_cpu_used, 0), enc + ": option cpu-used");
    check(av_opt_set(c->priv_data, "usage", p.aom_usage.c_str(), 0), enc + ": option usage");
    check(av_opt_set_int(c->priv_data, "row-mt", 0, 0), enc + ": option row-mt");
  } else if (p.encoder == "libx265") {
    check(av_opt_set(c->priv_data, "preset", p.x265_preset.c_str(), 0), enc + ": option preset");
    check(av_opt_set_double(c->priv_data, "crf", p.crf, 0), enc + ": option crf");
    check(av_opt_set(c->priv_data, "x265-params", "log-level=error:pools=none:frame-threads=1:open-gop=0", 0),
          enc + ": option x265-params");
  } else {
    throw std::runtime_error("unsupported encoder '" + p.encoder + "' (libaom-av1, libx265)");
  }
  check(avcodec_open2(c.get(), codec, nullptr), "avcodec_open2 (" + enc + ", yuv444p)");

  EncodedGroup out;
  out.frames = n;
  const ColourConverter rgb_to_yuv(size, true);
  PacketPtr pkt = make_packet();
  auto drain = [&](bool until_eof) {
    for (;;) {
      const int r = avcodec_receive_packet(c.get(), pkt.get());
      if (r == AVERROR(EAGAIN) && !until_eof) return;
      if (r == AVERROR_EOF) return;
      check(r, "avcodec_receive_packet (" + enc + ")");
      StreamPacket sp;
      sp.data.assign(pkt->data, pkt->data + pkt->size);
      sp.pts = pkt->pts;
      sp.dts = pkt->dts;
      sp.flags = pkt->flags;
      out.bytes += sp.data.size();
      out.packets.push_back(std::move(sp));
      av_packet_unref(pkt.get());
    }
  };
  for (int i = 0; i < n; ++i) {
    FramePtr f = make_frame();
    f->format = AV_PIX_FMT_YUV444P;
    f->width = f->height = size;
    f->color_range = AVCOL_RANGE_JPEG;
    f->colorspace = AVCOL_SPC_BT470BG;
    check(av_frame_get_buffer(f.get(), 0), "av_frame_get_buffer");
    rgb_to_yuv.to_yuv(*frames[std::size_t(i)], *f);
    f->pts = i;
    check(avcodec_send_frame(c.get(), f.get()), "avcodec_send_frame (" + enc + ")");
    drain(false);
  }
  check(avcodec_send_frame(c.get(), nullptr), "avcodec_send_frame flush (" + enc + ")");
  drain(true);
  out.encode_ms = ms_between(t0, Clock::now());
  if (out.packets.empty() || !(out.packets.front().flags & AV_PKT_FLAG_KEY))
    throw std::runtime_error(enc + ": the group's stream does not start with a keyframe");
  return out;
}

struct DecodedGroup {
  std::vector<std::vector<Rgba8>> frames;  // by pts
  // ready_ms[k]: decoder set-up + decoding every packet up to frame k's
  // output + frame k's conversion to RGBA: decoding frame k alone.
  std::vector<double> ready_ms;
  double total_ms = 0;  // the whole group, every frame converted
};

// Decodes `g` with decoder `name` ("libdav1d", "hevc") on one thread.
inline DecodedGroup decode_group(const EncodedGroup& g, const std::string& name, int size) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const AVCodec* codec = avcodec_find_decoder_by_name(name.c_str());
  if (!codec) throw std::runtime_error("libavcodec has no decoder '" + name + "'");
  CodecContextPtr c(avcodec_alloc_context3(codec));
  if (!c) throw std::runtime_error("avcodec_alloc_context3 failed");
  c->thread_count = 1;
  c->thread_type = 0;
  c->flags |= AV_CODEC_FLAG_LOW_DELAY;
  const std::string dec = "decoder " + name;
  check(avcodec_open2(c.get(), codec, nullptr), "avcodec_open2 (" + dec + ")");
  const ColourConverter yuv_to_rgb(size, false);
  double convert_ms = 0;  // conversions of earlier frames: not part of a later frame's cost

  DecodedGroup out;
  out.frames.resize(std::size_t(g.frames));
  out.ready_ms.assign(std::size_t(g.frames), -1);
  FramePtr frame = make_frame();
  auto receive = [&](bool until_eof) {
    for (;;) {
      const int r = avcodec_receive_frame(c.get(), frame.get());
      if (r == AVERROR(EAGAIN) && !until_eof) return;
      if (r == AVERROR_EOF) return;
      check(r, "avcodec_receive_frame (" + dec + ")");
      const double decoded_at = ms_between(t0, Clock::now()) - convert_ms;
      const std::int64_t k = frame->best_effort_timestamp != AV_NOPTS_VALUE ? frame->best_effort_timestamp : frame->pts;
      if (k < 0 || k >= g.frames || out.ready_ms[std::size_t(k)] >= 0)
        throw std::runtime_error(dec + ": unexpected frame timestamp " + std::to_string(k));
      const auto c0 = Clock::now();
      out.frames[std::size_t(k)] = yuv_to_rgb.to_rgba(*frame);
      const double conv = ms_between(c0, Clock::now());
      convert_ms += conv;
      out.ready_ms[std::size_t(k)] = decoded_at + conv;
      av_frame_unref(frame.get());
    }
  };
  PacketPtr pkt = make_packet();
  for (const StreamPacket& sp : g.packets) {
    check(av_new_packet(pkt.get(), int(sp.data.size())), "av_new_packet");
    std::memcpy(pkt->data, sp.data.data(), sp.data.size());
    pkt->pts = sp.pts;
    pkt->dts = sp.dts;
    pkt->flags = sp.flags;
    for (;;) {
      const int r = avcodec_send_packet(c.get(), pkt.get());
      if (r == AVERROR(EAGAIN)) {  // output first, then send the same packet again
        receive(false);
        continue;
      }
      check(r, "avcodec_send_packet (" + dec + ")");
      break;
    }
    av_packet_unref(pkt.get());
    receive(false);
  }
  check(avcodec_send_packet(c.get(), nullptr), "avcodec_send_packet flush (" + dec + ")");
  receive(true);
  out.total_ms = ms_between(t0, Clock::now());
  for (int k = 0; k < g.frames; ++k)
    if (out.ready_ms[std::size_t(k)] < 0) throw std::runtime_error(dec + ": frame " + std::to_string(k) + " never came out");
  return out;
}

}  // namespace cellbake::video
