// bricklayer-study-session: one subject's study session on the bus. See the file comment of
// bricklayer/study/session_node.h (what it subscribes to and publishes) and modules/study/README.md.
#include "bricklayer/runtime/node_main.h"
#include "bricklayer/study/session_node.h"

int main(int argc, char** argv) { return bricklayer::runtime::node_main<bricklayer::study::SessionNode>(argc, argv); }
