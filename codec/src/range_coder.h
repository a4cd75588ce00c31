#pragma once
// Private: an adaptive binary range coder (the LZMA design: 11-bit
// probabilities adapted by 1/32 per bit, carry propagation through a cache
// byte), and the integer models built on it. The decoder treats its input as
// hostile: reading past the end yields zero bytes, never an out-of-bounds
// access, and every decoded value is bounded by construction.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace isowave::detail {

using Probability = std::uint16_t;
constexpr int kProbabilityBits = 11;
constexpr Probability kProbabilityHalf = 1 << (kProbabilityBits - 1);
constexpr int kAdaptShift = 5;
constexpr std::uint32_t kTop = 1u << 24;

class RangeEncoder {
 public:
  explicit RangeEncoder(std::string& out) : out_(out) {}

  void encode_bit(Probability& p, int bit) {
    const std::uint32_t bound = (range_ >> kProbabilityBits) * p;
    if (bit == 0) {
      range_ = bound;
      p = static_cast<Probability>(p + (((1 << kProbabilityBits) - p) >> kAdaptShift));
    } else {
      low_ += bound;
      range_ -= bound;
      p = static_cast<Probability>(p - (p >> kAdaptShift));
    }
    while (range_ < kTop) {
      range_ <<= 8;
      shift_low();
    }
  }

  void encode_direct(std::uint32_t value, int bits) {
    for (int i = bits - 1; i >= 0; --i) {
      range_ >>= 1;
      if ((value >> i) & 1u) low_ += range_;
      while (range_ < kTop) {
        range_ <<= 8;
        shift_low();
      }
    }
  }

  void finish() {
    for (int i = 0; i < 5; ++i) shift_low();
  }

  // Flushes the shortest stream a PrefixRangeDecoder reads exactly: the value
  // in the final interval with the most trailing zero bits, without the
  // leading byte (always 0) and the trailing zero bytes (the decoder of a
  // complete packet reads zeros past its end). `first` is out_'s size when
  // this encoder started.
  void finish_trimmed(std::size_t first) {
    const std::uint64_t high = low_ + range_ - 1;
    for (int bits = 32; bits >= 0; --bits) {
      const std::uint64_t mask = (std::uint64_t{1} << bits) - 1;
      const std::uint64_t v = (low_ + mask) & ~mask;
      if (v <= high) {
        low_ = v;
        break;
      }
    }
    finish();
    out_.erase(out_.begin() + static_cast<std::ptrdiff_t>(first));  // the leading 0
    while (out_.size() > first && out_.back() == 0) out_.pop_back();
  }

 private:
  void shift_low() {
    if (static_cast<std::uint32_t>(low_) < 0xFF000000u || (low_ >> 32) != 0) {
      const auto carry = static_cast<std::uint8_t>(low_ >> 32);
      std::uint8_t temp = cache_;
      do {
        out_.push_back(static_cast<char>(static_cast<std::uint8_t>(temp + carry)));
        temp = 0xFF;
      } while (--cache_size_ != 0);
      cache_ = static_cast<std::uint8_t>(low_ >> 24);
    }
    ++cache_size_;
    low_ = (low_ & 0x00FFFFFFu) << 8;
  }

  std::string& out_;
  std::uint64_t low_ = 0;
  std::uint32_t range_ = 0xFFFFFFFFu;
  std::uint8_t cache_ = 0;
  std::uint64_t cache_size_ = 1;
};

// One adaptive binary decision of a decoder: the bit, with its code value,
// range and probability updated (normalization is the caller's).
inline int decide(std::uint32_t& code, std::uint32_t& range, Probability& p, std::uint32_t bound) {
  if (code < bound) {
    range = bound;
    p = static_cast<Probability>(p + (((1 << kProbabilityBits) - p) >> kAdaptShift));
    return 0;
  }
  code -= bound;
  range -= bound;
  p = static_cast<Probability>(p - (p >> kAdaptShift));
  return 1;
}

class RangeDecoder {
 public:
  RangeDecoder(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {
    for (int i = 0; i < 5; ++i) code_ = (code_ << 8) | next_byte();
  }

  int decode_bit(Probability& p) {
    const int bit = decide(code_, range_, p, (range_ >> kProbabilityBits) * p);
    while (range_ < kTop) {
      range_ <<= 8;
      code_ = (code_ << 8) | next_byte();
    }
    return bit;
  }

  std::uint32_t decode_direct(int bits) {
    std::uint32_t value = 0;
    for (int i = 0; i < bits; ++i) {
      range_ >>= 1;
      std::uint32_t bit = 0;
      if (code_ >= range_) {
        code_ -= range_;
        bit = 1;
      }
      value = (value << 1) | bit;
      while (range_ < kTop) {
        range_ <<= 8;
        code_ = (code_ << 8) | next_byte();
      }
    }
    return value;
  }

  // True if the decoder consumed more bytes than it was given (a sign of a
  // corrupt or hostile stream).
  bool overran() const { return position_ > size_ + 4; }

 private:
  std::uint32_t next_byte() { return position_ < size_ ? data_[position_++] : (++position_, 0u); }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t position_ = 0;
  std::uint32_t code_ = 0;
  std::uint32_t range_ = 0xFFFFFFFFu;
};

// The decoder of one packet written by RangeEncoder::finish_trimmed(). A
// complete packet reads zeros past its end, as its encoder trimmed them. A
// packet cut short (a file prefix) does not know its missing bytes: the
// decoder tracks how far they could move its code value and stops at the
// first decision they could change, so every decision it returns is the
// encoder's. Once stopped() it returns 0 bits and reads nothing. The ending
// is a template argument: a complete packet's decoder never stops, and its
// hot loop carries none of the cut's checks.
enum class PacketEnding { Complete, Cut };
template <PacketEnding kEnding>
class PrefixRangeDecoder {
 public:
  PrefixRangeDecoder(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {
    for (int i = 0; i < 4; ++i) code_ = (code_ << 8) | next_byte();
  }

  int decode_bit(Probability& p) {
    const std::uint32_t bound = (range_ >> kProbabilityBits) * p;
    if constexpr (kEnding == PacketEnding::Cut) {
      if (stopped_) return 0;
      if (unknown_ != 0 && code_ < bound && std::uint64_t{code_} + unknown_ >= bound) return stop();
    }
    const int bit = decide(code_, range_, p, bound);
    while (range_ < kTop) {
      range_ <<= 8;
      code_ = (code_ << 8) | next_byte();
    }
    return bit;
  }

  bool stopped() const { return kEnding == PacketEnding::Cut && stopped_; }

 private:
  int stop() {
    stopped_ = true;
    return 0;
  }
  std::uint32_t next_byte() {
    if (position_ < size_) return data_[position_++];
    ++position_;
    // Past a cut the byte is unknown: the code value may be up to
    // `unknown_` larger than with zeros (all of it after 4 such bytes).
    if constexpr (kEnding == PacketEnding::Cut) unknown_ = unknown_ >= 0x00FFFFFFu ? 0xFFFFFFFFu : (unknown_ << 8) | 0xFFu;
    return 0u;
  }

  const std::uint8_t* data_;
  std::size_t size_;
  bool stopped_ = false;
  std::size_t position_ = 0;
  std::uint32_t code_ = 0;
  std::uint32_t unknown_ = 0;
  std::uint32_t range_ = 0xFFFFFFFFu;
};

// A signed integer as magnitude class (bit length of |v|, 0..32) coded with an
// adaptive binary tree, then an adaptive sign bit, then the bits below the
// leading one: the top two adaptively per class, the rest directly.
struct IntegerModel {
  std::array<Probability, 64> class_tree;
  Probability sign;
  std::array<std::array<Probability, 4>, 33> high_bits;

  IntegerModel() {
    class_tree.fill(kProbabilityHalf);
    sign = kProbabilityHalf;
    for (auto& row : high_bits) row.fill(kProbabilityHalf);
  }
};

inline int bit_length(std::uint32_t v) { return v == 0 ? 0 : 32 - __builtin_clz(v); }

inline void encode_integer(RangeEncoder& rc, IntegerModel& m, std::int64_t value) {
  const std::uint32_t magnitude = static_cast<std::uint32_t>(value < 0 ? -value : value);
  const int k = bit_length(magnitude);
  // Class k in 0..32 as 6 bits through the tree.
  std::uint32_t node = 1;
  for (int i = 5; i >= 0; --i) {
    const int bit = (k >> i) & 1;
    rc.encode_bit(m.class_tree[node & 63], bit);
    node = (node << 1) | static_cast<std::uint32_t>(bit);
  }
  if (k == 0) return;
  rc.encode_bit(m.sign, value < 0 ? 1 : 0);
  int remaining = k - 1;
  // Top two bits below the leading one, adaptively.
  std::uint32_t context = 1;
  for (int i = 0; i < 2 && remaining > 0; ++i) {
    --remaining;
    const int bit = (magnitude >> remaining) & 1;
    rc.encode_bit(m.high_bits[static_cast<std::size_t>(k)][context], bit);
    context = (context << 1) | static_cast<std::uint32_t>(bit);
  }
  if (remaining > 0) rc.encode_direct(magnitude & ((1u << remaining) - 1u), remaining);
}

inline std::int64_t decode_integer(RangeDecoder& rc, IntegerModel& m) {
  std::uint32_t node = 1;
  for (int i = 0; i < 6; ++i) node = (node << 1) | static_cast<std::uint32_t>(rc.decode_bit(m.class_tree[node & 63]));
  const int k = static_cast<int>(node - 64);
  if (k == 0) return 0;
  if (k > 32) return 0;  // impossible in a valid stream; the caller's checks reject the result
  const bool negative = rc.decode_bit(m.sign) != 0;
  std::uint64_t magnitude = 1;
  int remaining = k - 1;
  std::uint32_t context = 1;
  for (int i = 0; i < 2 && remaining > 0; ++i) {
    --remaining;
    const int bit = rc.decode_bit(m.high_bits[static_cast<std::size_t>(k)][context]);
    context = (context << 1) | static_cast<std::uint32_t>(bit);
    magnitude = (magnitude << 1) | static_cast<std::uint64_t>(bit);
  }
  if (remaining > 0) magnitude = (magnitude << remaining) | rc.decode_direct(remaining);
  return negative ? -static_cast<std::int64_t>(magnitude) : static_cast<std::int64_t>(magnitude);
}

}  // namespace isowave::detail
