#include "flowfusion/io/cdr.h"

#include <algorithm>
#include <cstring>

namespace ff {

namespace {

constexpr size_t kHeaderBytes = 4;  // encapsulation kind (2 bytes, big endian) and options (2 bytes)
constexpr uint16_t kCdrBe = 0x0000, kCdrLe = 0x0001;

}  // namespace

CdrReader::CdrReader(const uint8_t* data, size_t size) {
  if (size < kHeaderBytes) throw CdrError("message of " + std::to_string(size) + " bytes has no CDR header");
  const uint16_t kind = uint16_t(data[0] << 8 | data[1]);
  if (kind != kCdrBe && kind != kCdrLe)
    throw CdrError("CDR encapsulation 0x" + std::to_string(data[0]) + "," + std::to_string(data[1]) +
                   " is not plain CDR (XCDR1 little or big endian); XCDR2 and parameter lists are not read");
  big_endian_ = kind == kCdrBe;
  data_ = data + kHeaderBytes;
  size_ = size - kHeaderBytes;
}

void CdrReader::align(size_t n) { pos_ = std::min(size_, (pos_ + n - 1) / n * n); }

const uint8_t* CdrReader::take(size_t n, const char* what) {
  if (n > size_ - pos_)
    throw CdrError(std::string("message ends inside its ") + what + " (needs " + std::to_string(n) + " bytes at " +
                   std::to_string(pos_) + " of " + std::to_string(size_) + ")");
  const uint8_t* p = data_ + pos_;
  pos_ += n;
  return p;
}

uint8_t CdrReader::u8() { return *take(1, "uint8"); }

uint32_t CdrReader::u32() {
  align(4);
  uint8_t b[4];
  std::memcpy(b, take(4, "uint32"), 4);
  if (big_endian_) std::reverse(b, b + 4);
  return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
}

double CdrReader::f64() {
  align(8);
  uint8_t b[8];
  std::memcpy(b, take(8, "float64"), 8);
  if (big_endian_) std::reverse(b, b + 8);
  uint64_t bits = 0;
  for (int i = 7; i >= 0; --i) bits = bits << 8 | b[i];
  double v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

std::string CdrReader::string() {
  const uint32_t n = u32();
  const uint8_t* p = take(n, "string");
  if (n == 0) return "";  // some writers omit the NUL of an empty string
  if (p[n - 1] != 0) throw CdrError("string of " + std::to_string(n) + " bytes does not end in NUL");
  return std::string(reinterpret_cast<const char*>(p), n - 1);
}

const uint8_t* CdrReader::bytes(size_t& count) {
  count = u32();
  return take(count, "uint8[] data");
}

std::vector<double> CdrReader::f64Sequence() {
  const uint32_t n = u32();
  if (n > (size_ - pos_) / 8) throw CdrError("float64[] of " + std::to_string(n) + " values is longer than the message");
  std::vector<double> out(n);
  for (double& v : out) v = f64();
  return out;
}

namespace {

// std_msgs/msg/Header: builtin_interfaces/Time stamp (int32 sec, uint32 nanosec), string frame_id.
RosStamp header(CdrReader& r) {
  RosStamp t;
  t.sec = r.i32();
  t.nsec = r.u32();
  if (t.nsec >= 1000000000u) throw CdrError("header stamp nanoseconds " + std::to_string(t.nsec) + " >= 1e9");
  r.string();
  return t;
}

}  // namespace

RosImage decodeRos2Image(const uint8_t* data, size_t size) {
  CdrReader r(data, size);
  RosImage m;
  m.stamp = header(r);
  m.height = r.u32();
  m.width = r.u32();
  m.encoding = r.string();
  m.big_endian = r.u8() != 0;
  m.step = r.u32();
  m.data = r.bytes(m.size);
  return m;
}

RosImage decodeRos2CompressedImage(const uint8_t* data, size_t size) {
  CdrReader r(data, size);
  RosImage m;
  m.compressed = true;
  m.stamp = header(r);
  m.encoding = r.string();
  m.data = r.bytes(m.size);
  return m;
}

RosCameraInfo decodeRos2CameraInfo(const uint8_t* data, size_t size) {
  CdrReader r(data, size);
  RosCameraInfo c;
  header(r);
  c.height = r.u32();
  c.width = r.u32();
  c.distortion_model = r.string();
  c.d = r.f64Sequence();
  for (double& k : c.k) k = r.f64();
  return c;
}

}  // namespace ff
