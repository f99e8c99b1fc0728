#include <cstdio>
int main() { std::puts("tendril " TENDRIL_VERSION); }
