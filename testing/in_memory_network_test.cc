#include "testing/in_memory_network.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "base/error.h"
#include "proto/zmq_transport.h"

namespace ms {
namespace {

namespace fs = std::filesystem;

TEST(InMemoryNetwork, RoutesByPeerAndDropsMessagesForGonePeers) {
  auto network = InMemoryNetwork::Create();
  auto server = network->Bind();
  auto a = network->Connect();
  auto b = network->Connect();
  a->Send("from a");
  b->Send("from b");
  PeerMessage m1, m2;
  ASSERT_TRUE(server->Receive(1.0, &m1));
  ASSERT_TRUE(server->Receive(1.0, &m2));
  EXPECT_EQ(m1.payload, "from a");
  EXPECT_EQ(m2.payload, "from b");
  EXPECT_NE(m1.peer, m2.peer);
  server->Send(m2.peer, "to b");
  std::string got;
  EXPECT_FALSE(a->Receive(0.01, &got));
  ASSERT_TRUE(b->Receive(1.0, &got));
  EXPECT_EQ(got, "to b");
  const std::string a_peer = m1.peer;
  a.reset();
  server->Send(a_peer, "lost");  // no crash, no effect
  PeerMessage none;
  EXPECT_FALSE(server->Receive(0.01, &none));
}

TEST(InMemoryNetwork, ReceiveWakesUpOnAMessageFromAnotherThread) {
  auto network = InMemoryNetwork::Create();
  auto server = network->Bind();
  auto client = network->Connect();
  std::thread sender([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    client->Send("late");
  });
  PeerMessage message;
  EXPECT_TRUE(server->Receive(5.0, &message));
  EXPECT_EQ(message.payload, "late");
  sender.join();
}

TEST(ZmqTransport, RoundTripOnLoopback) {
  ZmqServerOptions server_options;
  server_options.bind = "tcp://127.0.0.1:*";
  auto server = MakeZmqServer(server_options);
  ASSERT_NE(server->Endpoint().find("tcp://127.0.0.1:"), std::string::npos);
  ZmqClientOptions client_options;
  client_options.connect = server->Endpoint();
  auto client = MakeZmqClient(client_options);
  client->Send("hello");
  PeerMessage message;
  ASSERT_TRUE(server->Receive(5.0, &message));
  EXPECT_EQ(message.payload, "hello");
  EXPECT_EQ(message.frames, 1);
  server->Send(message.peer, std::string(100000, 'y'));
  std::string reply;
  ASSERT_TRUE(client->Receive(5.0, &reply));
  EXPECT_EQ(reply.size(), 100000u);
  server->Send("no such peer", "dropped");  // silently dropped
}

TEST(ZmqTransport, LocalOnlyEndpoints) {
  for (const char* local :
       {"tcp://127.0.0.1:5555", "tcp://127.1.2.3:*", "tcp://localhost:5555", "tcp://[::1]:5555",
        "ipc:///tmp/ms.sock", "inproc://x", "tcp://127.0.0.1;10.0.0.1:5555"}) {
    EXPECT_TRUE(IsLocalOnlyEndpoint(local)) << local;
  }
  for (const char* reachable :
       {"tcp://*:5555", "tcp://0.0.0.0:5555", "tcp://10.0.0.1:5555", "tcp://node01:5555",
        "tcp://eth0:5555", "tcp://[::]:5555", "tcp://127.0.0.1.evil.org:5555", "tcp://1270.0.0.1:1",
        "tcp://127.0.0.1", "udp://127.0.0.1:5555"}) {
    EXPECT_FALSE(IsLocalOnlyEndpoint(reachable)) << reachable;
  }
}

TEST(ZmqTransport, BindFailureNamesTheAddress) {
  ZmqServerOptions options;
  options.bind = "tcp://256.1.1.1:1";
  try {
    MakeZmqServer(options);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tcp://256.1.1.1:1"), std::string::npos);
  }
}

class CurveTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!CurveAvailable()) GTEST_SKIP() << "libzmq without CURVE";
    dir_ = fs::path(::testing::TempDir()) / "curve_test";
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "allowed");
    WriteCurveKeyFiles(GenerateCurveKeyPair(), (dir_ / "server").string(), false);
    WriteCurveKeyFiles(GenerateCurveKeyPair(), (dir_ / "good").string(), false);
    WriteCurveKeyFiles(GenerateCurveKeyPair(), (dir_ / "bad").string(), false);
    fs::copy_file(dir_ / "good.key", dir_ / "allowed" / "good.key");
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(CurveTest, KeyFilesRoundTripAndAreChecked) {
  const CurveKeyPair pair = ReadCurveKeyFile((dir_ / "good.key_secret").string(), true);
  const CurveKeyPair pub = ReadCurveKeyFile((dir_ / "good.key").string(), false);
  EXPECT_EQ(pair.public_key, pub.public_key);
  EXPECT_TRUE(pub.secret_key.empty());
  EXPECT_EQ(fs::status(dir_ / "good.key_secret").permissions() & fs::perms::others_read,
            fs::perms::none);
  EXPECT_THROW(ReadCurveKeyFile((dir_ / "good.key").string(), true), InputError);
  EXPECT_THROW(WriteCurveKeyFiles(pair, (dir_ / "good").string(), false), InputError);
  std::ofstream(dir_ / "broken.key") << "public-key = \"tooshort\"\n";
  try {
    ReadCurveKeyFile((dir_ / "broken.key").string(), false);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("broken.key:1"), std::string::npos) << e.what();
  }
}

TEST_F(CurveTest, AllowedKeyConnectsAndOtherKeyIsRefused) {
  ZmqServerOptions server_options;
  server_options.bind = "tcp://127.0.0.1:*";
  server_options.curve_secret_key_file = (dir_ / "server.key_secret").string();
  server_options.curve_public_keys_dir = (dir_ / "allowed").string();
  auto server = MakeZmqServer(server_options);

  ZmqClientOptions good;
  good.connect = server->Endpoint();
  good.curve_server_key_file = (dir_ / "server.key").string();
  good.curve_secret_key_file = (dir_ / "good.key_secret").string();
  auto good_client = MakeZmqClient(good);
  good_client->Send("let me in");
  PeerMessage message;
  ASSERT_TRUE(server->Receive(5.0, &message));
  EXPECT_EQ(message.payload, "let me in");

  ZmqClientOptions bad = good;
  bad.curve_secret_key_file = (dir_ / "bad.key_secret").string();
  auto bad_client = MakeZmqClient(bad);
  bad_client->Send("let me in too");
  // The server handles the ZAP request while it waits; the client learns of the refusal.
  std::string reply;
  for (int i = 0; i < 50 && bad_client->AuthFailure().empty(); ++i) {
    EXPECT_FALSE(server->Receive(0.05, &message));
    bad_client->Receive(0.01, &reply);
  }
  EXPECT_NE(bad_client->AuthFailure().find("refused this worker's CURVE key"), std::string::npos)
      << bad_client->AuthFailure();
}

}  // namespace
}  // namespace ms
