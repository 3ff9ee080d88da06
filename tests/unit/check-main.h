/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* main() of a check program: one suite and test case of `name`, its tests
 * added by `add`; exit status 0 when all passed. */
#pragma once

#include <check.h>

static inline int check_main(const char *name, void (*add)(TCase *tc)) {
        Suite *s = suite_create(name);
        TCase *tc = tcase_create(name);
        tcase_set_timeout(tc, 60);
        add(tc);
        suite_add_tcase(s, tc);
        SRunner *sr = srunner_create(s);
        srunner_run_all(sr, CK_NORMAL);
        int failed = srunner_ntests_failed(sr);
        srunner_free(sr);
        return failed == 0 ? 0 : 1;
}
