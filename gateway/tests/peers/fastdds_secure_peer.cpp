// A secured ROS 2 node as rmw_fastrtps makes one, for the gateway's SROS2 tests: Fast DDS
// (Debian's libfastrtps, built with DDS Security; PyPI's rclpy wheels have none) with the
// security properties rmw_fastrtps sets from an enclave directory, publishing or
// subscribing std_msgs/msg/String on one topic as ROS 2 names it on DDS.
//
//   fastdds_secure_peer pub DOMAIN TOPIC ENCLAVE_DIR TEXT [SECONDS]   # "SENT n" per message
//   fastdds_secure_peer sub DOMAIN TOPIC ENCLAVE_DIR [SECONDS]        # "MSG text" per sample
//
// TOPIC is the ROS name (`/chatter` is DDS topic `rt/chatter`). Loopback UDP only.

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

#include <chrono>
#include <cstring>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

using namespace eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::InstanceHandle_t;
using eprosima::fastrtps::rtps::SerializedPayload_t;

// std_msgs/msg/String in CDR (little endian): encapsulation, then the string's length
// (with its NUL) and bytes.
class StringType : public TopicDataType {
public:
    StringType() {
        setName("std_msgs::msg::dds_::String_");
        m_typeSize = 4 + 4 + 65536;
        m_isGetKeyDefined = false;
    }
    bool serialize(void* data, SerializedPayload_t* payload) override {
        const std::string& s = *static_cast<std::string*>(data);
        uint32_t n = static_cast<uint32_t>(s.size() + 1);
        if (8 + n > payload->max_size) {
            return false;
        }
        const uint8_t head[4] = {0x00, 0x01, 0x00, 0x00};
        std::memcpy(payload->data, head, 4);
        std::memcpy(payload->data + 4, &n, 4);
        std::memcpy(payload->data + 8, s.c_str(), n);
        payload->length = 8 + n;
        payload->encapsulation = CDR_LE;
        return true;
    }
    bool deserialize(SerializedPayload_t* payload, void* data) override {
        if (payload->length < 8) {
            return false;
        }
        uint32_t n = 0;
        std::memcpy(&n, payload->data + 4, 4);
        if (n == 0 || 8 + n > payload->length) {
            return false;
        }
        static_cast<std::string*>(data)->assign(reinterpret_cast<char*>(payload->data + 8), n - 1);
        return true;
    }
    std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
        return [data]() { return static_cast<uint32_t>(8 + static_cast<std::string*>(data)->size() + 1); };
    }
    void* createData() override { return new std::string(); }
    void deleteData(void* data) override { delete static_cast<std::string*>(data); }
    bool getKey(void*, InstanceHandle_t*, bool) override { return false; }
};

int main(int argc, char** argv) {
    if (argc < 5) {
        std::cerr << "usage: fastdds_secure_peer pub|sub DOMAIN TOPIC ENCLAVE_DIR [TEXT] [SECONDS]\n";
        return 2;
    }
    const std::string mode = argv[1];
    const int domain = std::stoi(argv[2]);
    const std::string topic_name = std::string("rt") + argv[3];
    const std::string dir = argv[4];
    const std::string text = (mode == "pub" && argc > 5) ? argv[5] : "";
    const int seconds_arg = mode == "pub" ? 6 : 5;
    const double seconds = argc > seconds_arg ? std::stod(argv[seconds_arg]) : 10.0;

    DomainParticipantQos pqos;
    pqos.name("fastdds_secure_peer");
    // As rmw_fastrtps (apply_security_options): the builtin plugins on the enclave's files.
    auto& props = pqos.properties().properties();
    auto file = [&](const char* f) { return "file://" + dir + "/" + f; };
    props.emplace_back("dds.sec.auth.plugin", "builtin.PKI-DH");
    props.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_ca", file("identity_ca.cert.pem"));
    props.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_certificate", file("cert.pem"));
    props.emplace_back("dds.sec.auth.builtin.PKI-DH.private_key", file("key.pem"));
    props.emplace_back("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
    props.emplace_back("dds.sec.access.plugin", "builtin.Access-Permissions");
    props.emplace_back("dds.sec.access.builtin.Access-Permissions.permissions_ca",
                       file("permissions_ca.cert.pem"));
    props.emplace_back("dds.sec.access.builtin.Access-Permissions.governance", file("governance.p7s"));
    props.emplace_back("dds.sec.access.builtin.Access-Permissions.permissions", file("permissions.p7s"));
    // Loopback UDP only (no shared memory: a network namespace does not isolate /dev/shm).
    pqos.transport().use_builtin_transports = false;
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.emplace_back("127.0.0.1");
    pqos.transport().user_transports.push_back(udp);

    DomainParticipant* participant =
        DomainParticipantFactory::get_instance()->create_participant(domain, pqos);
    if (participant == nullptr) {
        std::cerr << "fastdds_secure_peer: cannot create a secured participant in " << dir << "\n";
        return 1;
    }
    TypeSupport type(new StringType());
    type.register_type(participant);
    Topic* topic = participant->create_topic(topic_name, type.get_type_name(), TOPIC_QOS_DEFAULT);
    if (topic == nullptr) {
        std::cerr << "fastdds_secure_peer: topic " << topic_name << " refused\n";
        return 1;
    }
    auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    int status = 0;
    if (mode == "pub") {
        Publisher* pub = participant->create_publisher(PUBLISHER_QOS_DEFAULT);
        DataWriterQos wqos = DATAWRITER_QOS_DEFAULT;
        wqos.reliability().kind = RELIABLE_RELIABILITY_QOS;
        DataWriter* writer = pub ? pub->create_datawriter(topic, wqos) : nullptr;
        if (writer == nullptr) {
            std::cerr << "fastdds_secure_peer: writer on " << topic_name << " refused\n";
            status = 1;
        }
        std::cout << "READY" << std::endl;
        for (int i = 0; writer && std::chrono::steady_clock::now() < end; ++i) {
            std::string msg = text;
            writer->write(&msg);
            std::cout << "SENT " << i << std::endl;
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
    } else {
        Subscriber* sub = participant->create_subscriber(SUBSCRIBER_QOS_DEFAULT);
        DataReaderQos rqos = DATAREADER_QOS_DEFAULT;
        rqos.reliability().kind = RELIABLE_RELIABILITY_QOS;
        DataReader* reader = sub ? sub->create_datareader(topic, rqos) : nullptr;
        if (reader == nullptr) {
            std::cerr << "fastdds_secure_peer: reader on " << topic_name << " refused\n";
            status = 1;
        }
        std::cout << "READY" << std::endl;
        while (reader && std::chrono::steady_clock::now() < end) {
            std::string msg;
            SampleInfo info;
            while (reader->take_next_sample(&msg, &info) == ReturnCode_t::RETCODE_OK) {
                if (info.valid_data) {
                    std::cout << "MSG " << msg << std::endl;
                }
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
    }
    participant->delete_contained_entities();
    DomainParticipantFactory::get_instance()->delete_participant(participant);
    return status;
}
