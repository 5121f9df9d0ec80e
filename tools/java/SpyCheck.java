// Decodes every event of an LCM log the way lcm-spy does: the type is found by its fingerprint
// among the classes on the classpath (lcm.spy.LCMTypeDatabase, the mvtrack types jar), then built
// from the bytes. Prints one line per channel (events, type, events decoded, a field or two of the
// last message) and exits 1 if any channel has an event that does not decode.
//
//   java -cp lcm.jar:mvtrack_lcmtypes.jar tools/java/SpyCheck.java LOG.lcm
import java.io.DataInputStream;
import java.io.ByteArrayInputStream;
import java.io.DataInput;
import java.io.EOFException;
import java.lang.reflect.Field;
import java.util.Map;
import java.util.TreeMap;

import lcm.logging.Log;
import lcm.spy.LCMTypeDatabase;

public class SpyCheck {
    static final class Chan {
        int events, decoded;
        String type = "?", sample = "", error = "";
    }

    public static void main(String[] args) throws Exception {
        if (args.length != 1) {
            System.err.println("usage: SpyCheck LOG.lcm");
            System.exit(2);
        }
        LCMTypeDatabase db = new LCMTypeDatabase();
        Map<String, Chan> chans = new TreeMap<>();
        Log log = new Log(args[0], "r");
        while (true) {
            Log.Event ev;
            try {
                ev = log.readNext();
            } catch (EOFException e) {
                break;
            }
            Chan c = chans.computeIfAbsent(ev.channel, k -> new Chan());
            c.events++;
            try {
                long fp = new DataInputStream(new ByteArrayInputStream(ev.data)).readLong();
                Class<?> cls = db.getClassByFingerprint(fp);
                if (cls == null) {
                    c.error = String.format("no type with fingerprint %016x on the classpath", fp);
                    continue;
                }
                Object o = cls.getConstructor(DataInput.class)
                              .newInstance(new DataInputStream(new ByteArrayInputStream(ev.data)));
                c.type = cls.getName();
                c.decoded++;
                StringBuilder sb = new StringBuilder();
                for (Field f : cls.getFields()) {
                    if (java.lang.reflect.Modifier.isStatic(f.getModifiers()) || f.getType().isArray()) {
                        continue;
                    }
                    if (sb.length() > 60) {
                        break;
                    }
                    sb.append(f.getName()).append('=').append(f.get(o)).append(' ');
                }
                c.sample = sb.toString().trim();
            } catch (Exception e) {
                c.error = e.toString();
            }
        }
        boolean ok = !chans.isEmpty();
        for (Map.Entry<String, Chan> e : chans.entrySet()) {
            Chan c = e.getValue();
            boolean good = c.decoded == c.events;
            ok &= good;
            System.out.printf("%-22s %6d events  %-26s %6d decoded  %s%s%n", e.getKey(), c.events, c.type, c.decoded,
                              good ? "" : "FAIL ", good ? c.sample : c.error);
        }
        System.exit(ok ? 0 : 1);
    }
}
