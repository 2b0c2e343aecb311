#include "jpcr/io/dds/dds_participant.hpp"

#include <iostream>
#include <map>
#include <mutex>

#include <dds/dds.h>

#include "jpcr/io/dds/dds_config.hpp"

namespace jpcr {

namespace {

// Cyclone keeps one domain per id per process. A domain created explicitly with a configuration
// (dds_create_domain) lives until it is deleted, so the participants that created it count
// their users here and the last one deletes it. This is the only shared state of the DDS layer.
struct ExplicitDomains {
  std::mutex mutex;
  std::map<int, std::pair<dds_entity_t, int>> domains;  // id -> (domain entity, users)
};

ExplicitDomains& explicit_domains() {
  static ExplicitDomains domains;
  return domains;
}

}  // namespace

std::int32_t check_dds(std::int32_t code, const std::string& call) {
  if (code < 0) throw DdsError(call + ": " + dds_strretcode(code));
  return code;
}

DdsParticipant::DdsParticipant(const DdsConfig& config)
    : DdsParticipant(config.domain_id, config.cyclone_uri) {}

DdsParticipant::DdsParticipant(int domain_id, const std::string& cyclone_uri)
    : domain_id_(domain_id) {
  if (domain_id < 0 || domain_id > 232) {
    throw DdsError("DDS domain id " + std::to_string(domain_id) + " is not in 0..232");
  }
  const auto id = static_cast<dds_domainid_t>(domain_id);
  {
    // Every participant of an explicitly created domain counts, configured or not.
    ExplicitDomains& registry = explicit_domains();
    std::lock_guard<std::mutex> lock(registry.mutex);
    auto it = registry.domains.find(domain_id);
    if (it != registry.domains.end()) {
      ++it->second.second;
      counted_domain_ = true;
    } else if (!cyclone_uri.empty()) {
      const dds_entity_t domain = dds_create_domain(id, cyclone_uri.c_str());
      if (domain >= 0) {
        registry.domains[domain_id] = {domain, 1};
        counted_domain_ = true;
      } else if (domain == DDS_RETCODE_PRECONDITION_NOT_MET) {  // exists: joined implicitly
        // (e.g. a ROS 2 node of this process with rmw_cyclonedds): its configuration holds.
        std::cerr << "jpcr dds: domain " << domain_id
                  << " already exists in this process; its Cyclone configuration holds and "
                     "cyclone_uri is not applied (MaxSampleSize, socket buffers)\n";
      } else {
        check_dds(domain,
                  "dds_create_domain(" + std::to_string(domain_id) + ", " + cyclone_uri + ")");
      }
    }
  }
  participant_ = dds_create_participant(id, nullptr, nullptr);
  if (participant_ < 0) {
    const std::int32_t code = participant_;
    participant_ = 0;
    release();  // the domain reference taken above
    check_dds(code, "dds_create_participant(domain " + std::to_string(domain_id) + ")");
  }
}

DdsParticipant::~DdsParticipant() {
  release();
}

void DdsParticipant::release() {
  if (participant_ > 0) dds_delete(participant_);
  participant_ = 0;
  if (!counted_domain_) return;
  counted_domain_ = false;
  ExplicitDomains& registry = explicit_domains();
  std::lock_guard<std::mutex> lock(registry.mutex);
  auto it = registry.domains.find(domain_id_);
  if (it != registry.domains.end() && --it->second.second == 0) {
    dds_delete(it->second.first);
    registry.domains.erase(it);
  }
}

}  // namespace jpcr
