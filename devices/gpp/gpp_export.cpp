// The GPP's device library (librsca-gpp.so): what rsca-noded looks up in it.
#include "gpp_device.hpp"
#include "node/device_export.hpp"

RSCA_DEVICES(rsca::gpp::register_gpp)
