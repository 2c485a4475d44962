"""rosbag2 bags in MCAP storage, as `ros2 bag record -s mcap` writes them in Jazzy.

    BAG/metadata.yaml        rosbag2_bagfile_information, version 9
    BAG/BAG_0.mcap           profile "ros2"; schema encoding ros2msg, message encoding cdr;
                             channel metadata offered_qos_profiles (YAML) and topic_type_hash

The file format is left to maintained libraries: `mcap` writes the MCAP files and,
when reading, parses their schema, channel and chunk records (decompression, CRC);
`rosbags` provides the message definitions, type hashes and the CDR decoder, and
reads sqlite3 bags. This package adds the rosbag2 layout around them. It knows
nothing of mill (no mill topic names, no runs); what a bag of a mill run means is
`mill_analysis.bag_run`.

Modules (each imports only those above it):

    errors     BagError: str() says in one line why a bag cannot be written or read
    cdr        cdr_stamp_ns (a message's leading stamp), joint_state_cdr (fast JointState)
    intake     Intake: what a recorder lets into a bag (stamps, size, CDR), drops counted
    types      message-type names, the typestore, definitions and RIHS01 hashes, decode()
    writer     BagWriter, TopicInfo, metadata.yaml; flush() closes an MCAP chunk; a full
               disk cuts the bag short at its last flush (BagCutShort, noted in metadata);
               a time MCAP cannot hold is refused before it touches the file
    mcap_index what an MCAP file's indexes say (summary, message indexes), checked
    mcap_read  McapFile: the messages of one MCAP file, whole or around its damaged parts
               (Damage: where, why, how many messages lost)
    reader     open_bag -> Bag; read() yields (topic, type, log_time, publish_time, data),
               a file without footer (a killed recording) up to its last complete chunk;
               Bag.cut_short says why a recording ended early, where the writer noted it
    recover    recover(): rewrite a killed or damaged file as a complete bag, keeping every
               message that reads (nothing changes if the disk has no room for it)
    recorder   TopicRecorder (raw subscriptions of any node -> Intake -> BagWriter) and the
               `recorder` node; the only module that needs rclpy

    python -m mill_bag recover BAG     # complete the file a SIGKILL left, or save a damaged one

Everything but `recorder` is ROS-free (no rclpy), so bags are read without a graph.
"""
