// A DDS domain participant (Cyclone DDS), owned. Every writer and reader of jpcr hangs off one.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace jpcr {

struct DdsConfig;

/// A failure of the DDS middleware itself (entity creation, write); names the call and the code.
class DdsError : public std::runtime_error {
 public:
  explicit DdsError(const std::string& what) : std::runtime_error(what) {}
};

class DdsParticipant {
 public:
  /// Joins `domain_id`. A non-empty `cyclone_uri` ("file://PATH" or inline XML) configures the
  /// domain when this process has not joined it yet; otherwise $CYCLONEDDS_URI does. Throws
  /// DdsError when Cyclone refuses (a bad configuration file, no usable interface).
  explicit DdsParticipant(int domain_id, const std::string& cyclone_uri = "");
  explicit DdsParticipant(const DdsConfig& config);
  ~DdsParticipant();
  DdsParticipant(const DdsParticipant&) = delete;
  DdsParticipant& operator=(const DdsParticipant&) = delete;

  /// The Cyclone entity handle (dds_entity_t).
  std::int32_t handle() const { return participant_; }
  int domain_id() const { return domain_id_; }

 private:
  void release();

  int domain_id_;
  std::int32_t participant_ = 0;
  bool counted_domain_ = false;  // this participant holds a reference to an explicit domain
};

/// Throws DdsError "<call>: <Cyclone's message>" when `code` is negative; returns it otherwise.
std::int32_t check_dds(std::int32_t code, const std::string& call);

}  // namespace jpcr
