#include "hardware/stream_decoder.h"

namespace graspbed::hardware {

void StreamDecoder::StartPacket() {
  size_ = 0;
  block_remaining_ = 0;
  block_code_ = 0;
  discarding_ = false;
}

void StreamDecoder::Reset() {
  StartPacket();
  synced_ = false;
}

void StreamDecoder::Fail(PacketError error) {
  last_error_ = error;
  if (!synced_) return;
  switch (error) {
    case PacketError::kCobs:
      ++stats_.cobs_errors;
      break;
    case PacketError::kCrc:
      ++stats_.crc_errors;
      break;
    case PacketError::kTooLong:
      ++stats_.too_long;
      break;
    case PacketError::kUnknownVersion:
      ++stats_.unknown_version;
      break;
    case PacketError::kUnknownType:
      ++stats_.unknown_type;
      break;
    case PacketError::kTooShort:
    case PacketError::kBadLength:
    case PacketError::kBadUnitCount:
    case PacketError::kBadHandCount:
      ++stats_.length_errors;
      break;
    case PacketError::kNone:
      break;
  }
}

bool StreamDecoder::Append(uint8_t byte) {
  if (size_ >= buffer_.size()) {
    Fail(PacketError::kTooLong);
    discarding_ = true;
    return false;
  }
  buffer_[size_++] = byte;
  return true;
}

bool StreamDecoder::Complete(DecodedPacket* packet) {
  if (block_remaining_ != 0) {
    Fail(PacketError::kCobs);
    return false;
  }
  if (size_ < kHeaderSize + kCrcSize) {
    Fail(PacketError::kTooShort);
    return false;
  }
  const size_t body_size = size_ - kCrcSize;
  const uint16_t received = static_cast<uint16_t>(buffer_[body_size] | (buffer_[body_size + 1] << 8));
  const std::span<const uint8_t> body(buffer_.data(), body_size);
  if (Crc16CcittFalse(body) != received) {
    Fail(PacketError::kCrc);
    return false;
  }
  // A good CRC means we are in step with the sender: from here on every refusal is counted, also
  // an unknown type or version that comes first after Reset().
  synced_ = true;
  const PacketError error = ParseBody(body, packet);
  if (error != PacketError::kNone) {
    const bool length = error == PacketError::kBadLength || error == PacketError::kBadHandCount;
    if (length && body[0] == static_cast<uint8_t>(PacketType::kHand)) ++stats_.hand_errors;
    Fail(error);
    return false;
  }
  ++stats_.packets;
  return true;
}

FeedResult StreamDecoder::Feed(std::span<const uint8_t> input, DecodedPacket* packet) {
  FeedResult result;
  for (const uint8_t byte : input) {
    ++result.consumed;
    ++stats_.bytes;
    if (byte == 0x00) {
      const bool was_discarding = discarding_;
      const bool empty = block_code_ == 0;
      const bool ok = !was_discarding && !empty && Complete(packet);
      StartPacket();
      if (ok) {
        result.packet = true;
        return result;
      }
      continue;  // errors are counted; an empty packet (two delimiters in a row) is not an error
    }
    if (discarding_) continue;
    if (block_remaining_ == 0) {
      // A code byte. The block before it, unless it was a full 254-byte block, stood for a zero.
      if (block_code_ != 0 && block_code_ != 0xFF && !Append(0x00)) continue;
      block_code_ = byte;
      block_remaining_ = byte - 1;
    } else {
      if (!Append(byte)) continue;
      --block_remaining_;
    }
  }
  return result;
}

}  // namespace graspbed::hardware
