/* The reset handler of every Cortex-M port: initialised data copied from flash, .bss
 * cleared, then main(); a main() that returns ends in the port's fault(). */
#include <string.h>

#include "cortexm.h"

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss;
int main(void);

void reset(void)
{
    memcpy(&_sdata, &_sidata, (size_t)((char *)&_edata - (char *)&_sdata));
    memset(&_sbss, 0, (size_t)((char *)&_ebss - (char *)&_sbss));
    main();
    fault();
}
